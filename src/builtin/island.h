// builtin:island, a tropical island after Disney's Moana island scene: its
// 20 elements by name (isBayCedarA1 .. osOcean), each several meshes; the
// terrain elements are the ground cut into tiles by region plus their set
// pieces, and every element instances its own species over its own region.
// Lit by a sun, a sky and a campfire with lanterns on the beach.
//
// Views: "default" (from the shore towards the peaks), "beach" (low on the
// beach, at the campfire) and "overview" (high above the whole island).
//
// Scale s (default 1) keeps the island's size and grows its detail: s times
// the instances, sqrt(s) times the cells per side. kIslandLargeScale is a
// scale to describe (`ferry info`) or spread over ranks, not to generate on
// one small machine. Counts per scale: docs/scenes.md, "builtin:island".
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

constexpr double kIslandLargeScale = 100;

ScenePlan planIsland(double scale, uint32_t seed);

}  // namespace ferry::builtin
