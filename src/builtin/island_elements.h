// The island's element table, after Disney's Moana island (docs/scenes.md):
// its 20 elements by name, and what each one instances: the plant element's
// own plant (its copies over the element's region) and the species each
// element scatters over its region (Moana's per-element "instanced
// primitives"), with counts at scale 1. The species and their numbers of
// variants are those of Disney's element files, the prototypes' sizes those
// of its archives; the instance counts, not published per element, are set
// so that the island-wide ratios match the published ones (docs/scenes.md).
// None is tuned towards a rendering or partitioning result.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "builtin/island_shape.h"
#include "builtin/plants.h"
#include "builtin/vegetation.h"

namespace ferry::builtin {

constexpr std::array<const char*, 20> kIslandElements = {
    "isBayCedarA1", "isBeach",     "isCoastline", "isCoral",         "isDunesA",
    "isDunesB",     "isGardeniaA", "isHibiscus",  "isHibiscusYoung", "isIronwoodA1",
    "isIronwoodB",  "isKava",      "isLavaRocks", "isMountainA",     "isMountainB",
    "isNaupakaA",   "isPalmDead",  "isPalmRig",   "isPandanusA",     "osOcean"};

// The stand-in shapes, each a design from plants.h with its own parameters.
enum class PlantKind {
  Broadleaf,   // ironwood, bay cedar
  Breadfruit,  // lower detail
  Canopy,      // lowest detail: a crown of large leaf cards
  Palm,
  DeadPalm,
  Pandanus,
  Bush,  // hibiscus, gardenia, naupaka, kava
  YoungBush,
  Fern,
  Grass,
  Seaweed,
  Flowers,
  Pebble,
  Shell,
  Stone,
  Rock,
  Boulder,
  Debris,  // fallen palm fronds' ribs and branches
  AntlerCoral,
  CabbageCoral,
};

struct ElementSpecies {
  std::string element;
  std::string name;
  PlantKind kind;
  double count;  // instances at scale 1
  int variants;  // objects at scale 1
  Region region;
  ScatterRule rule;
};

// Every element's instanced species, in a fixed order (the species' random
// streams follow it). isIronwoodA1's own giant tree is not in it: its first
// copy is the hero of the default view (island.cpp).
std::vector<ElementSpecies> islandSpecies();

// Variant v of a kind; a pure function of (kind, v, seed).
PlantDesign designPlant(PlantKind kind, int v, uint32_t seed);

}  // namespace ferry::builtin
