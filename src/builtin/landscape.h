// builtin:landscape, after pbrt-v4's "landscape" scene: rolling meadows
// crossed by a dirt path, a bald knoll at the back, and many unique plant
// meshes (hundreds of variants of oaks, pines, birches, shrubs, ferns, grass,
// flowers, rocks and logs, each variant its own object) instanced tens of
// thousands of times, with several alpha-cut leaf, needle, frond and petal
// textures.
//
// Views: "path" (standing on the path), "view-3" (across the meadow to the
// knoll) and "top" (straight down on the whole terrain).
//
// Scale s (default 1): instances of every species grow as s (at least one
// per variant); terrain cells per side as 512 sqrt(s) (64 .. 16384) and the
// terrain texture as about 1024 sqrt(s) texels (256 .. 8192); the set of
// variants (and so the unique plant geometry) stays the same.
// At s = 1: 186 plant objects of 346 meshes, 1.25 M unique and 5.8e7
// instanced triangles, 40 K instances, 13 textures (7 with alpha cut-outs),
// about 0.6 s of CPU time to generate.
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

ScenePlan planLandscape(double scale, uint32_t seed);

}  // namespace ferry::builtin
