#include "trace/proxy_bvh.h"

#include <algorithm>
#include <cmath>

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
  order_.resize(proxies_.size());
  for (size_t i = 0; i < order_.size(); ++i) order_[i] = int32_t(i);
  if (!proxies_.empty()) build(0, int32_t(proxies_.size()), 0);
}

int32_t ProxyBvh::build(int32_t first, int32_t count, int depth) {
  int32_t index = int32_t(nodes_.size());
  nodes_.push_back({});
  Box3f bounds, centers;
  RankMask owners = 0;
  for (int32_t i = first; i < first + count; ++i) {
    const Proxy& p = proxies_[order_[i]];
    bounds.extend(p.bounds);
    centers.extend(p.bounds.center());
    owners |= p.owners;
  }
  nodes_[index].bounds = bounds;
  nodes_[index].ownersUnion = owners;
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
                     float ca = proxies_[a].bounds.center()[axis], cb = proxies_[b].bounds.center()[axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  int32_t left = build(first, mid - first, depth + 1);
  int32_t right = build(mid, first + count - mid, depth + 1);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

ProxyBvh::Hit ProxyBvh::closest(Vec3f origin, Vec3f direction, float tmax, RankMask excluded) const {
  Hit best;
  if (nodes_.empty()) return best;
  Vec3f inv{1 / direction.x, 1 / direction.y, 1 / direction.z};
  int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if ((node.ownersUnion & ~excluded) == 0) continue;  // every proxy below is excluded
    float tNode;
    // Strictly closer, or equally close (a lower index may still win the tie).
    if (!intersectBox(node.bounds, origin, inv, std::min(tmax, std::nextafter(best.tEnter, kInfinity)), tNode))
      continue;
    if (node.left < 0) {
      for (int32_t i = node.first; i < node.first + node.count; ++i) {
        int32_t id = order_[i];
        const Proxy& p = proxies_[id];
        if (p.owners & excluded) continue;
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
