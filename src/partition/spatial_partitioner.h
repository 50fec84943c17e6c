// Spatial partitioning (paper, Section 4; after Zellmann et al.): each part
// is a domain box; a split cuts the domain in two non-overlapping halves, and
// each unit goes to every half its box overlaps (content straddling the
// plane goes to both sides). Each half's domain then shrinks to the content
// it holds (intersected with the half). The proxies are the domain boxes.
//
// Why that is enough for correct traversal: every point of a unit's box lies
// in the domain of some part that holds the unit (true for the root, and each
// split keeps it: a point left of the plane is in the left half, whose unit
// list has every unit reaching left of the plane, and the shrunk domain still
// holds every such unit's box clipped to the half). Partition::checkCovers
// checks exactly this, by union of proxies.
#pragma once

#include "partition/split_loop.h"

namespace ferry {

enum class SpatialSplitRule {
  Median,        // spatial-simple: the spatial median of the domain's longest axis
  CostFunction,  // spatial-sah: the best of 3 x 7 equidistant planes by splitCost()
};

class SpatialSplitter final : public PartSplitter {
 public:
  SpatialSplitter(const UnitSet& units, SpatialSplitRule rule) : PartSplitter(units), rule_(rule) {}
  bool split(const Part& part, Part& left, Part& right) override;

 private:
  // Sides of `part` for the plane; false if one side is empty.
  bool divide(const Part& part, int axis, float position, Part& left, Part& right);
  SpatialSplitRule rule_;
};

// One proxy per part: its domain, owned by the part's ranks.
std::vector<Proxy> domainProxies(const std::vector<Part>& parts,
                                 const std::vector<RankSet>& partRanks);

}  // namespace ferry
