#include "partition/ray_guided_partitioner.h"

#include <gtest/gtest.h>

namespace ferry {
namespace {

// `count` units in a row along x, unit u in [u, u + 1], each its own object
// with its own mesh of `ownBytes`, and unit u also using shared mesh u % `shared`
// of `sharedBytes` (objects instanced all over, in turn: a part holding any
// of a mesh's users pays for it once).
UnitSet rowSharingMeshes(uint32_t count, uint64_t ownBytes, uint32_t shared, uint64_t sharedBytes) {
  UnitSet set;
  set.resourceBytes.assign(shared, sharedBytes);
  for (uint32_t u = 0; u < count; ++u) {
    set.resourceBytes.push_back(ownBytes);
    Unit unit;
    unit.object = int32_t(u);
    unit.firstResource = uint32_t(set.resources.size());
    unit.resourceCount = 2;
    set.resources.push_back(u % shared);
    set.resources.push_back(shared + u);
    unit.bounds = {{float(u), 0, 0}, {float(u) + 1, 1, 1}};
    set.units.push_back(unit);
  }
  set.meshResources = uint32_t(set.resourceBytes.size());
  set.objectCount = count;
  return set;
}

// With a large --max-part the parts may each hold every shared mesh: 64
// units in a row, 4 shared meshes (40 % of the bytes) used in turn, rays only
// between neighbours. Cut into 8 runs of neighbours, a part holds 40 % +
// 7.5 %, within 4.2 x an even share (52.5 %), and 7 boundaries are crossed.
// Halving bytes level by level (beta) cannot reach that (at the third level
// a side keeps 86 % of its parent: the shared meshes do not halve), and
// bringing the sides under beta by moving all the users of a shared mesh to
// the other side scattered them (the landscape's parts at --max-part 4.2
// were interleaved patches): a side within the final limit is balanced.
TEST(RayGuidedSplitter, ASideWithinTheFinalLimitIsBalancedEvenIfSharedContentDoesNotHalve) {
  const uint32_t count = 64;
  const UnitSet units = rowSharingMeshes(count, 60, 4, 640);
  Hypergraph rays;
  for (uint32_t u = 0; u + 1 < count; ++u)
    for (int copies = 0; copies < 4; ++copies) {
      rays.units.push_back(u);
      rays.units.push_back(u + 1);
      rays.offsets.push_back(rays.units.size());
    }
  RayGuidedSplitter splitter(units, rays, 8, 4.2);
  const std::vector<Part> parts = runSplitLoop(splitter, 8);
  ASSERT_EQ(parts.size(), 8u);
  for (const Part& p : parts) {
    ASSERT_FALSE(p.units.empty());
    // A run of neighbours: no unit of another part in between.
    EXPECT_EQ(p.units.back() - p.units.front() + 1, p.units.size());
    EXPECT_LE(double(p.bytes), (4.2 - kRayGuidedRefineMargin) * 6400.0 / 8);
  }
  EXPECT_EQ(estimatedForwards(rays, parts, units.units.size()), 7u * 4u);
}

}  // namespace
}  // namespace ferry
