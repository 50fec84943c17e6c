// A BVH over proxies, on every rank, answering the forwarding operator's
// question: along this ray, before tmax, which is the closest proxy none of
// whose owners the ray has visited? Ties in entry distance go to the lower
// proxy index, so every rank answers identically.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/math.h"
#include "partition/partition.h"

namespace ferry {

class ProxyBvh {
 public:
  ProxyBvh() = default;
  explicit ProxyBvh(std::vector<Proxy> proxies);

  struct Hit {
    int32_t proxy = -1;
    float tEnter = kInfinity;
    bool found() const { return proxy >= 0; }
  };
  // Closest proxy entered in [0, tmax) whose owners do not intersect `excluded`.
  // The answer is a pure function of the set of such proxies (least entry
  // distance, then least index): the entry distance of a proxy does not
  // depend on tmax, so a smaller tmax only drops candidates from the far end.
  // The replay layout relies on this (distributed/forwarding.h).
  Hit closest(Vec3f origin, Vec3f direction, float tmax, RankMask excluded) const;
  // The same for any rank count (used by the replay layout; a few words per
  // test instead of one above 64 ranks).
  Hit closest(Vec3f origin, Vec3f direction, float tmax, const RankSet& excluded) const;
  // True when every owner is below rank 64 (the RankMask query is exact).
  bool narrow() const { return wideUnion_.empty(); }

  const std::vector<Proxy>& proxies() const { return proxies_; }
  size_t nodeCount() const { return nodes_.size(); }

 private:
  template <typename Excluded>
  Hit closestImpl(Vec3f origin, Vec3f direction, float tmax, const Excluded& excluded) const;

  struct Node {
    Box3f bounds;
    RankMask ownersUnion = 0;  // lets a subtree whose proxies are all excluded be skipped (narrow)
    int32_t left = -1, right = -1;  // children; -1 in a leaf
    int32_t first = 0, count = 0;   // leaf range in order_
    int32_t minIndex = 0;           // least proxy index below: prunes ties (closestImpl)
  };
  int32_t build(int32_t first, int32_t count, int depth, const std::vector<Vec3f>& centers);
  // An inner node's two children as the query reads them: both boxes, owner
  // masks and least indices in one record (one cache line or two), instead
  // of a load from each child node before deciding whether to enter it.
  struct Children {
    Box3f bounds[2];
    RankMask owners[2];
    int32_t minIndex[2];
    int32_t node[2];
  };

  std::vector<Proxy> proxies_;
  std::vector<RankMask> ownerMasks_;  // per proxy (narrow)
  std::vector<RankSet> wideUnion_;    // per node, only when some owner is rank 64 or above
  std::vector<int32_t> order_;
  std::vector<Box3f> leafBounds_;    // proxies' boxes in leaf order (order_)
  std::vector<RankMask> leafMasks_;  // their owner masks (narrow), in leaf order
  std::vector<Node> nodes_;
  std::vector<Children> children_;  // per node (inner nodes only are read)
};

// Whether the ray enters `box` before tmax; entry distance clamped at 0
// (origin inside counts as entering at 0).
[[gnu::always_inline]] inline bool intersectBox(const Box3f& box, Vec3f origin,
                                                Vec3f inverseDirection, float tmax, float& tEnter) {
  float t0 = 0, t1 = tmax;
  if (!box.clipRay(origin, inverseDirection, t0, t1)) return false;
  tEnter = t0;
  return t0 < tmax;
}

}  // namespace ferry
