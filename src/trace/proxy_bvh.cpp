#include "trace/proxy_bvh.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace ferry {
namespace {
constexpr int kLeafSize = 4;
}

bool intersectBox(const Box3f& box, Vec3f origin, Vec3f inv, float tmax, float& tEnter) {
  float t0 = 0, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    float lo = (box.lower[a] - origin[a]) * inv[a];
    float hi = (box.upper[a] - origin[a]) * inv[a];
    if (lo > hi) std::swap(lo, hi);
    // NaN (0 * inf: origin on a slab plane of a zero direction) means inside that slab.
    if (!(lo <= hi)) continue;
    t0 = std::max(t0, lo);
    t1 = std::min(t1, hi);
    if (t0 > t1) return false;
  }
  tEnter = t0;
  return t0 < tmax;
}

ProxyBvh::ProxyBvh(std::vector<Proxy> proxies) : proxies_(std::move(proxies)) {
  bool wide = false;
  for (const Proxy& p : proxies_) {
    ownerMasks_.push_back(p.owners.mask());
    wide = wide || !p.owners.fitsInMask();
  }
  if (wide) wideUnion_.push_back({});  // marks the BVH wide; filled per node by build
  order_.resize(proxies_.size());
  for (size_t i = 0; i < order_.size(); ++i) order_[i] = int32_t(i);
  if (!proxies_.empty()) build(0, int32_t(proxies_.size()), 0);
}

int32_t ProxyBvh::build(int32_t first, int32_t count, int depth) {
  int32_t index = int32_t(nodes_.size());
  nodes_.push_back({});
  Box3f bounds, centers;
  RankMask owners = 0;
  RankSet wideOwners;
  for (int32_t i = first; i < first + count; ++i) {
    const Proxy& p = proxies_[order_[i]];
    bounds.extend(p.bounds);
    centers.extend(p.bounds.center());
    owners |= p.owners.mask();
    if (!narrow()) wideOwners |= p.owners;
  }
  nodes_[index].bounds = bounds;
  nodes_[index].ownersUnion = owners;
  if (!narrow()) {
    if (wideUnion_.size() <= size_t(index)) wideUnion_.resize(size_t(index) + 1);
    wideUnion_[size_t(index)] = std::move(wideOwners);
  }
  if (count <= kLeafSize || depth > 60) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  // Median split on the longest axis of the centres: simple, balanced, deterministic.
  int axis = centers.longestAxis();
  int32_t mid = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                   [&](int32_t a, int32_t b) {
                     float ca = proxies_[a].bounds.center()[axis],
                           cb = proxies_[b].bounds.center()[axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  int32_t left = build(first, mid - first, depth + 1);
  int32_t right = build(mid, first + count - mid, depth + 1);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

namespace {
// The two ways of asking "are all of these owners excluded / is any excluded".
struct MaskExclusion {
  RankMask excluded;
};
struct SetExclusion {
  const RankSet& excluded;
};
}  // namespace

ProxyBvh::Hit ProxyBvh::closest(Vec3f origin, Vec3f direction, float tmax,
                                RankMask excluded) const {
  if (narrow()) return closestImpl(origin, direction, tmax, MaskExclusion{excluded});
  const RankSet set = RankSet::fromMask(excluded);
  return closestImpl(origin, direction, tmax, SetExclusion{set});
}

ProxyBvh::Hit ProxyBvh::closest(Vec3f origin, Vec3f direction, float tmax,
                                const RankSet& excluded) const {
  // Narrow: owners are all below 64, so only the first word of `excluded` matters.
  if (narrow()) return closestImpl(origin, direction, tmax, MaskExclusion{excluded.mask()});
  return closestImpl(origin, direction, tmax, SetExclusion{excluded});
}

template <typename Excluded>
ProxyBvh::Hit ProxyBvh::closestImpl(Vec3f origin, Vec3f direction, float tmax,
                                    const Excluded& ex) const {
  constexpr bool kMask = std::is_same_v<Excluded, MaskExclusion>;
  Hit best;
  if (nodes_.empty()) return best;
  Vec3f inv{1 / direction.x, 1 / direction.y, 1 / direction.z};
  int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int32_t nodeIndex = stack[--top];
    const Node& node = nodes_[nodeIndex];
    // Every proxy below is excluded.
    if constexpr (kMask) {
      if ((node.ownersUnion & ~ex.excluded) == 0) continue;
    } else {
      if (wideUnion_[size_t(nodeIndex)].isSubsetOf(ex.excluded)) continue;
    }
    float tNode;
    // Strictly closer, or equally close (a lower index may still win the tie).
    if (!intersectBox(node.bounds, origin, inv,
                      std::min(tmax, std::nextafter(best.tEnter, kInfinity)), tNode))
      continue;
    if (node.left < 0) {
      for (int32_t i = node.first; i < node.first + node.count; ++i) {
        int32_t id = order_[i];
        const Proxy& p = proxies_[id];
        if constexpr (kMask) {
          if (ownerMasks_[size_t(id)] & ex.excluded) continue;
        } else {
          if (p.owners.intersects(ex.excluded)) continue;
        }
        float t;
        if (!intersectBox(p.bounds, origin, inv, tmax, t)) continue;
        if (t < best.tEnter || (t == best.tEnter && id < best.proxy)) best = {id, t};
      }
    } else {
      stack[top++] = node.right;
      stack[top++] = node.left;
    }
  }
  return best;
}

}  // namespace ferry
