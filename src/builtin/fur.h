// builtin:fur?strands=N, curve data at any size for tests, benches and the
// viewer: a ball covered by N hair strands (default 10000), each a cubic
// Bézier curve of 4 segments (a flat, ray-facing fibre; shapes/curves.h)
// with pbrt's hair material, on a grey floor and backdrop under daylight.
// The ratios are a groom's, in centimetres: 300 strands per cm² over the
// ball's upper 70 % (the ball's radius follows from N: 19.5 cm at a
// million strands), strands 2 cm long (at most half the radius), 80 µm wide
// at the root tapering to 20 µm at the tip, combed back and down. The
// strands are one geometry (partitioning cuts it into pieces: partition/
// scene_split.h). View "default" looks at the ball from the front.
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr uint64_t kDefaultFurStrands = 10000;
constexpr int kFurSegmentsPerStrand = 4;

ScenePlan planFur(uint64_t strands, uint32_t seed);

}  // namespace ferry::builtin
