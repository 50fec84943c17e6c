#include "partition/part_assignment.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace ferry {
namespace {

// A unit set by hand: unit u of object objects[u] (-1: none), ownBytes
// own[u], using resources uses[u].
UnitSet makeUnits(const std::vector<int32_t>& objects, const std::vector<uint64_t>& own,
                  const std::vector<std::vector<uint32_t>>& uses,
                  const std::vector<uint64_t>& resourceBytes) {
  UnitSet set;
  set.resourceBytes = resourceBytes;
  set.meshResources = uint32_t(resourceBytes.size());
  set.objectCount = 0;
  for (size_t u = 0; u < objects.size(); ++u) {
    Unit unit;
    unit.object = objects[u];
    unit.ownBytes = own[u];
    unit.firstResource = uint32_t(set.resources.size());
    unit.resourceCount = uint32_t(uses[u].size());
    set.resources.insert(set.resources.end(), uses[u].begin(), uses[u].end());
    unit.bounds = {{float(u), 0, 0}, {float(u) + 1, 1, 1}};
    set.units.push_back(unit);
    set.objectCount = std::max(set.objectCount, uint32_t(objects[u] + 1));
  }
  return set;
}

std::vector<uint32_t> iota(size_t n) {
  std::vector<uint32_t> v(n);
  for (uint32_t i = 0; i < n; ++i) v[i] = i;
  return v;
}

uint64_t bruteForceScore(const Hypergraph& rays, const PartAssignment& a) {
  uint64_t score = 0;
  for (size_t r = 0; r < rays.rays(); ++r) {
    std::vector<int> parts;
    for (uint64_t e = rays.offsets[r]; e < rays.offsets[r + 1]; ++e)
      parts.push_back(a.partOf(rays.units[e]));
    std::sort(parts.begin(), parts.end());
    score += size_t(std::unique(parts.begin(), parts.end()) - parts.begin()) - 1;
  }
  return score;
}

Hypergraph makeRays(const std::vector<std::vector<uint32_t>>& rows) {
  Hypergraph h;
  for (const auto& row : rows) {
    h.units.insert(h.units.end(), row.begin(), row.end());
    h.offsets.push_back(h.units.size());
  }
  return h;
}

// Two clusters of three units, each cluster passed by one ray, and one ray
// between them: dealt alternately, every ray spans both parts (score 3);
// refined, the clusters come together and only the bridge is cut.
TEST(PartAssignment, RefineGathersWhatRaysPassTogether) {
  const UnitSet set =
      makeUnits({-1, -1, -1, -1, -1, -1}, {10, 10, 10, 10, 10, 10}, {{}, {}, {}, {}, {}, {}}, {});
  const Hypergraph rays = makeRays({{0, 1, 2}, {3, 4, 5}, {2, 3}});
  PartAssignment a(set, iota(6), rays, 2, {0, 1, 0, 1, 0, 1});
  EXPECT_EQ(a.score(), 3u);
  EXPECT_EQ(a.bytes(0), 30u);
  a.refine(40);
  EXPECT_EQ(a.score(), bruteForceScore(rays, a));
  EXPECT_EQ(a.score(), 1u);
  EXPECT_LE(a.largest(), 40u);
  EXPECT_EQ(a.partOf(0), a.partOf(1));
  EXPECT_EQ(a.partOf(1), a.partOf(2));
  EXPECT_EQ(a.partOf(3), a.partOf(4));
  EXPECT_NE(a.partOf(0), a.partOf(3));
}

// The limit binds: the one unit away from the ray's others may join them
// only where a part may hold all four.
TEST(PartAssignment, RefineNeverExceedsTheLimit) {
  const UnitSet set = makeUnits({-1, -1, -1, -1}, {10, 10, 10, 10}, {{}, {}, {}, {}}, {});
  const Hypergraph rays = makeRays({{0, 1, 2, 3}});
  PartAssignment a(set, iota(4), rays, 2, {0, 0, 0, 1});
  a.refine(30);  // the move would put 40 bytes in part 0
  EXPECT_EQ(a.score(), 1u);
  EXPECT_EQ(a.largest(), 30u);
  a.refine(40);
  EXPECT_EQ(a.score(), 0u);
  EXPECT_EQ(a.bytes(0), 40u);
  EXPECT_EQ(a.bytes(1), 0u);
}

// Gathering a shared mesh's users frees a copy (less over all parts) but may
// pile them on one part: moving part 0's two instances to part 1, which
// holds the mesh too, lowers the total excess (84 -> 44) and makes part 1
// 104 bytes, more than any part held before. Such rounds are undone.
TEST(PartAssignment, RebalanceNeverGrowsTheLargestPart) {
  const UnitSet set = makeUnits({0, 0, 0, 0, -1}, {1, 1, 1, 1, 1}, {{0}, {0}, {0}, {0}, {}}, {100});
  const Hypergraph rays = makeRays({});
  PartAssignment a(set, iota(5), rays, 3, {0, 0, 1, 1, 2});
  EXPECT_EQ(a.largest(), 102u);
  a.rebalance(60);
  EXPECT_LE(a.largest(), 102u);
}

// All eight units in one part, two objects of four instances each sharing
// a 100-byte mesh: moving single instances frees a byte a move while the
// other part pays the whole mesh; moving one object's instances together
// frees its mesh. Rebalanced, each part holds one object.
TEST(PartAssignment, RebalanceMovesAnObjectsInstancesTogether) {
  const UnitSet set = makeUnits({0, 0, 0, 0, 1, 1, 1, 1}, {1, 1, 1, 1, 1, 1, 1, 1},
                                {{0}, {0}, {0}, {0}, {1}, {1}, {1}, {1}}, {100, 100});
  const Hypergraph rays = makeRays({});
  PartAssignment a(set, iota(8), rays, 2, {0, 0, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(a.bytes(0), 208u);
  a.rebalance(110);
  EXPECT_EQ(a.bytes(0), 104u);
  EXPECT_EQ(a.bytes(1), 104u);
  for (uint32_t u = 1; u < 4; ++u) EXPECT_EQ(a.partOf(u), a.partOf(0));
  for (uint32_t u = 5; u < 8; ++u) EXPECT_EQ(a.partOf(u), a.partOf(4));
}

// Shared content paid twice: each part holds instances of both objects, so
// each pays both meshes (204 > 2 x 110 together); moving all users of one
// mesh out of a part frees its copy.
TEST(PartAssignment, RebalanceFreesASharedCopy) {
  const UnitSet set = makeUnits({0, 0, 1, 1, 0, 0, 1, 1}, {1, 1, 1, 1, 1, 1, 1, 1},
                                {{0}, {0}, {1}, {1}, {0}, {0}, {1}, {1}}, {100, 100});
  const Hypergraph rays = makeRays({{0, 4}, {2, 6}});  // rays tie the copies of an object
  PartAssignment a(set, iota(8), rays, 2, {0, 0, 0, 0, 1, 1, 1, 1});
  EXPECT_EQ(a.bytes(0), 204u);
  EXPECT_EQ(a.score(), 2u);
  a.rebalance(110);
  EXPECT_LE(a.largest(), 110u);
  EXPECT_EQ(a.score(), bruteForceScore(rays, a));
  EXPECT_EQ(a.score(), 0u);  // each object gathered in one part
}

}  // namespace
}  // namespace ferry
