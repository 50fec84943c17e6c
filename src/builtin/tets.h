// builtin:tets?count=N: an unstructured volume of about N tetrahedra (a
// lattice of cubes, each cut into six along its diagonal, conforming), a
// smooth ball of values through the standard transfer function, over a
// floor under daylight: unstructured data at any size without a download.
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr uint64_t kDefaultTets = 1000000;

// The value at `p` in [-1, 1]^3 (in [0, 1]): what the lattice's points hold.
float tetsField(Vec3f p);
// Cubes along each side for about `count` tetrahedra (6 per cube), at least 1.
uint32_t tetsCubesPerSide(uint64_t count);
ScenePlan planTets(uint64_t count, uint32_t seed);

}  // namespace ferry::builtin
