// builtin:furnace, the white furnace test: a diffuse sphere (radius 1 at the
// origin, base colour 0.8) inside a constant white environment (radiance 1),
// no sun. The sphere is convex, so every path leaving it escapes: a correct
// path tracer renders the sphere at exactly 0.8 everywhere and the background
// at 1, whatever the lighting or sampling strategy. (0.8 rather than 1 so a
// renderer that drops or double-counts a bounce shows it.) View "default"
// looks at the sphere from z = 4.
//
// Scale s (default 1) refines the tessellation: 64 sqrt(s) latitudes and
// 128 sqrt(s) longitudes (rounded to keep the poles and equator exact).
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr float kFurnaceAlbedo = 0.8f;

ScenePlan planFurnace(double scale, uint32_t seed);

}  // namespace ferry::builtin
