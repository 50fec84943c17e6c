// builtin:island, a tropical island after Disney's Moana island scene: one
// large textured heightfield terrain, set pieces overlapping it (a volcanic
// mountain, sea cliffs, a sand beach), an ocean, a giant banyan as the hero
// object, and ten instanced species spread or clustered over the land (trees,
// palms, bushes, ferns, grass, flowers, rocks, boulders, driftwood), lit by a
// sun, a sky and a campfire with lanterns on the beach.
//
// Views: "default" (from the shore towards the mountain), "beach" (low on
// the beach, at the campfire) and "overview" (high above the whole island).
//
// Scale s (default 1) keeps the island's size and grows its detail:
//   - instances of every species: s times the scale-1 count (at least 1),
//   - terrain cells per side: 1024 sqrt(s) (64 .. 16384), set pieces likewise,
//   - terrain texture: about 1024 sqrt(s) texels per side (256 .. 8192),
//   - variants per species: floor(sqrt(s)) times the scale-1 number (up to 32x),
//   - banyans: floor(sqrt(s)) (at least one); below s = 1 the banyan also
//     thins (fewer leaves and roots), so small scales make small scenes.
// At s = 1: 2.9 M unique and 1.9e8 instanced triangles, 71 K instances,
// about 1 s of CPU time to generate (spread over the cores), 110 MB resident.
// At s = 0.1: 0.6 M unique triangles, 7 K instances (for tests).
// At s = kIslandLargeScale = 100 the description (made without generating)
// is 2.4e8 unique and 2.0e10 instanced triangles, 7.1 M instances and an
// estimated 23 GiB: meant for `ferry info` and for spreading over ranks,
// not for generating on one small machine.
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr double kIslandLargeScale = 100;

ScenePlan planIsland(double scale, uint32_t seed);

}  // namespace ferry::builtin
