// Object-space partitioning (paper, Section 4): a unit is never cut; a split
// sorts each unit left or right of a plane by the centre of its box (for an
// object: the box around all its instances), trying 3 axes x 7 equidistant
// planes across the part's unit centres and keeping the one of least
// splitCost(). The object partitioners use one unit per object (all its
// instances on one rank).
//
// The hybrid partitioners (bvh-style, best) use the same splitter with one
// unit per instance, sorted by its own centre. `best` adds `groupCandidates`:
// another 3 x 7 planes that sort the instances of each object together, by
// the box around that object's instances in the part, so the cost function
// chooses between splitting an object's instances (each side pays for its
// meshes) and keeping them together (docs/partitioning.md, "`best`'s extra
// candidates").
#pragma once

#include "partition/split_loop.h"

namespace ferry {

struct Scene;

class CentroidSplitter final : public PartSplitter {
 public:
  CentroidSplitter(const UnitSet& units, bool groupCandidates)
      : PartSplitter(units), groupCandidates_(groupCandidates) {}
  bool split(const Part& part, Part& left, Part& right) override;

 private:
  bool groupCandidates_;
};

// The key points a split sorts a part's units by, one family per way of
// sorting (k indexes part.units): the units' own box centres, and with
// `groupCandidates` (when some object has several instances in the part)
// the centre of the box around each object's instances in the part.
// `placed[k]`: the unit has geometry (units without always go left).
std::vector<std::vector<Vec3f>> unitKeyFamilies(const UnitSet& units, const Part& part,
                                                bool groupCandidates, std::vector<uint8_t>& placed);

// The two sides `plane` makes of a part's units, sorted by `key` (units
// without geometry go left): their costs (counters cleared first) and boxes.
// Returns how many units went left.
size_t planeSides(const UnitSet& units, const Part& part, const std::vector<uint8_t>& placed,
                  const std::vector<Vec3f>& key, const SplitPlane& plane, CostCounter& leftCost,
                  CostCounter& rightCost, Box3f& leftBox, Box3f& rightBox);

// object-naive: one proxy per unit, its box.
std::vector<Proxy> unitBoxProxies(const UnitSet& units, const std::vector<RankSet>& owners);

}  // namespace ferry
