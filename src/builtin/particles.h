// builtin:particles?count=N, particle data at any size (a simulation's
// output, atoms): N spheres (default 100 000) in five Gaussian clusters
// within [-1.1, 1.1]^3, radii about half the mean spacing, over a grey floor
// and backdrop under daylight. One geometry (shapes/spheres.h), which the
// best partitioner cuts into spatial pieces (partition/scene_split.h).
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr uint64_t kDefaultParticles = 100000;

ScenePlan planParticles(uint64_t count, uint32_t seed);

}  // namespace ferry::builtin
