// builtin:volume, a procedural cloud of any size for tests and benchmarks:
// a grid medium of size^3 samples (default 64; `size` = 512 is 512 MiB of
// densities) over the box [-1, 1]^3, bounded by that box, above a grey
// ground under daylight. The density is a ball fading out towards the box's
// faces, roughened by 3-D gradient noise (from the seed), within [0, 1];
// sigma_a 1, sigma_s 24 per unit length (albedo 0.96), Henyey-Greenstein g 0.4.
// View "default" looks at it from the front and a little above.
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr int kDefaultVolumeSize = 64;

ScenePlan planVolume(int size, uint32_t seed);

}  // namespace ferry::builtin
