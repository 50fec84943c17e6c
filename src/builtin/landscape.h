// builtin:landscape, after pbrt's "landscape" scene: rolling meadows crossed
// by a dirt path, a knoll at the back; the ground (tiles of one object,
// placed once) and tree and ground-cover models of several meshes each,
// instanced over it, with alpha-cut leaf, needle, frond and petal textures.
//
// Views: "path" (standing on the path), "view-3" (across the meadow to the
// knoll) and "top" (straight down on the whole terrain).
//
// Scale s (default 1) grows every instance count by s and the ground's cells
// per side by sqrt(s); the models stay the same. Counts per scale:
// docs/scenes.md, "builtin:landscape".
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

ScenePlan planLandscape(double scale, uint32_t seed);

}  // namespace ferry::builtin
