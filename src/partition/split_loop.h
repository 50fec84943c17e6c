// The loop every partitioner shares (paper, Section 4): start with one part
// holding every unit, then split the costliest part in two until there are
// N parts. Partitioners differ only in how they split one part (PartSplitter)
// and in the proxies they make afterwards.
//
// A part of one unit is never split (cutting large units is the scene
// transformation's job, see scene_split.h). When no part can be split any
// more and ranks remain, the spare ranks hold copies of the costliest parts
// (replication), so that no rank is left without content.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/math.h"
#include "partition/partition.h"
#include "partition/units.h"

namespace ferry {

struct Part {
  std::vector<uint32_t> units;  // ascending unit ids
  Box3f domain;        // spatial partitioners: the (shrunk) domain; others: bounds of the units
  uint64_t bytes = 0;  // memory estimate, shared content counted once
  bool splittable = true;
};

class PartSplitter {
 public:
  virtual ~PartSplitter() = default;
  // The part holding everything.
  virtual Part root();
  // Splits `part` into two non-empty parts (which may share units: spatial
  // splits put straddling content on both sides), their `bytes` filled in.
  // Returns false if this part cannot be split.
  virtual bool split(const Part& part, Part& left, Part& right) = 0;

 protected:
  explicit PartSplitter(const UnitSet& units) : units_(units), counter_(units) {}
  uint64_t bytesOf(const std::vector<uint32_t>& members);
  Box3f boundsOf(const std::vector<uint32_t>& members) const;

  const UnitSet& units_;
  CostCounter counter_;
};

// Runs the loop until there are `parts` parts or none can be split. `observe`
// (optional) sees the parts after every step: 1, 2, ... parts.
std::vector<Part> runSplitLoop(PartSplitter& splitter, int parts,
                               const std::function<void(const std::vector<Part>&)>& observe = {});

// Ranks for each part: part k gets rank k; ranks beyond the part count are
// dealt to the parts in decreasing cost (ties: lower index), as copies.
std::vector<RankSet> assignRanks(const std::vector<Part>& parts, int ranks);

// Owners of each unit: the ranks of every part holding it.
std::vector<RankSet> unitOwners(const UnitSet& units, const std::vector<Part>& parts,
                                const std::vector<RankSet>& partRanks);

// Owners per scene instance, from owners per unit.
std::vector<RankSet> instanceOwnersOf(const UnitSet& units, const std::vector<RankSet>& owners);

// The split cost the cost-function partitioners minimize: a 50:50 blend of
// SAH (each side's surface area times its memory estimate, relative to the
// parent's) and the memory estimate (the two sides' bytes plus their
// difference, relative to the parent's: twice the larger side). The paper
// blends SAH with the *sum* of the sides' memory; a plain sum rewards slicing
// a sliver off a part (sum = parent, whatever the balance), which does not
// reduce the largest part, so the imbalance is charged too.
double splitCost(const Box3f& parent, uint64_t parentBytes, const Box3f& left, uint64_t leftBytes,
                 const Box3f& right, uint64_t rightBytes);

// 3 axes x 7 equidistant planes strictly inside `bounds` (degenerate axes skipped).
struct SplitPlane {
  int axis = 0;
  float position = 0;
};
std::vector<SplitPlane> candidatePlanes(const Box3f& bounds, int perAxis = 7);

}  // namespace ferry
