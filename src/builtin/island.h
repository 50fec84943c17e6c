// builtin:island, a tropical island after Disney's Moana island scene
// (docs/scenes.md): its 20 elements by name (isBayCedarA1 .. osOcean), each
// several meshes. The terrain elements (two volcanic peaks, dunes, beach,
// coastline, lava cliffs, reef, ocean) are the ground cut into tiles by
// region plus their set pieces; every element instances its own species over
// its own region, and each plant element copies its own plant there, so what
// grows varies over the island. Lit by a sun, a sky and a campfire with
// lanterns on the beach.
//
// Views: "default" (from the shore towards the peaks), "beach" (low on the
// beach, at the campfire) and "overview" (high above the whole island).
//
// Scale s (default 1) keeps the island's size and grows its detail:
//   - instances of every species: s times the scale-1 count (at least 1),
//   - ground cells per side: 16 tiles of 32 sqrt(s) (4 .. 512) cells; the
//     peaks, cliffs, beach and reef likewise grow with sqrt(s) per side,
//   - ground texture: about 768 sqrt(s) texels per side (256 .. 8192),
//   - variants per species: floor(sqrt(s)) times the scale-1 number (up to
//     32x), and below s = 1 about sqrt(s) times it (at least one),
//   - below s = 1 isIronwoodA1's giant tree also thins (fewer leaves and
//     roots), so small scales make small scenes.
// At s = 1: 1.8 M unique and 4.3e8 instanced triangles, 126 K instances,
// 245 MiB estimated (ratios after the published Moana figures, docs/scenes.md).
// At s = 0.1: 0.64 M unique triangles, 13 K instances (for tests).
// At s = kIslandLargeScale = 100 the description (made without generating)
// is 6.7e7 unique and 4.4e10 instanced triangles, 13 M instances and an
// estimated 11 GiB: meant for `ferry info` and for spreading over ranks,
// not for generating on one small machine.
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr double kIslandLargeScale = 100;

ScenePlan planIsland(double scale, uint32_t seed);

}  // namespace ferry::builtin
