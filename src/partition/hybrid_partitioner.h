// Hybrid partitioning (paper, Section 4): instances, not objects, are the
// units, so an object is replicated on every rank where its instances land
// (bvh-style). `best` first cuts large meshes into tight pieces (see
// scene_split.h), partitions like bvh-style, then replicates spatially large
// but cheap content on every rank, up to a byte budget: a ray already on a
// rank then finds it there instead of being forwarded.
#pragma once

#include <cstdint>
#include <vector>

#include "partition/split_loop.h"

namespace ferry {

struct ReplicationResult {
  uint64_t addedBytes = 0;  // summed over ranks: what the copies cost
  uint64_t replicatedUnits = 0;
};

// A unit counts as spatially large when its box's surface area is at least
// this fraction of the box around everything. Low on purpose: candidates are
// taken by area per byte, so the budget goes to the cheapest large things
// first (the island's ocean and seabed, then terrain pieces); at 1/64 only
// the sea qualified and most of the budget stayed unused.
constexpr double kLargeAreaFraction = 1.0 / 4096.0;

// Adds copies of spatially large units to every part, largest surface area per
// byte first, as long as the bytes added over all ranks stay within `budget`
// (a unit that does not fit is skipped; smaller ones may still fit), and,
// when `maxPartBytes` > 0, no part grows beyond it. Updates `parts` (units,
// bytes) and `owners` (per unit).
ReplicationResult replicateLargeUnits(const UnitSet& units, std::vector<Part>& parts,
                                      const std::vector<RankSet>& partRanks,
                                      std::vector<RankSet>& owners, uint64_t budget,
                                      uint64_t maxPartBytes = 0);

}  // namespace ferry
