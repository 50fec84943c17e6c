#include "trace/proxy_bvh.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <type_traits>

namespace ferry {
namespace {
constexpr int kLeafSize = 4;

// The next float above t >= 0 (nextafter(t, inf) without the libm call,
// which showed in profiles): one step of the bit pattern; infinity stays.
// Above 0 (and the denormals) it is the smallest normal float: Ferry runs
// with denormals read as zero (core/floating_point_mode.h), so the smallest
// denormal would compare equal to 0 and a tie at t = 0 (the ray starting
// inside two proxies) would lose its lower index.
inline float nextAbove(float t) {
  if (t == kInfinity) return t;
  if (t < std::numeric_limits<float>::min()) return std::numeric_limits<float>::min();
  return std::bit_cast<float>(std::bit_cast<uint32_t>(t) + 1u);
}
}  // namespace

ProxyBvh::ProxyBvh(std::vector<Proxy> proxies) : proxies_(std::move(proxies)) {
  bool wide = false;
  for (const Proxy& p : proxies_) {
    ownerMasks_.push_back(p.owners.mask());
    wide = wide || !p.owners.fitsInMask();
  }
  if (wide) wideUnion_.push_back({});  // marks the BVH wide; filled per node by build
  order_.resize(proxies_.size());
  for (size_t i = 0; i < order_.size(); ++i) order_[i] = int32_t(i);
  if (proxies_.empty()) return;
  std::vector<Vec3f> centers(proxies_.size());
  for (size_t i = 0; i < proxies_.size(); ++i) centers[i] = proxies_[i].bounds.center();
  build(0, int32_t(proxies_.size()), 0, centers);
  children_.resize(nodes_.size());
  for (size_t n = 0; n < nodes_.size(); ++n) {
    if (nodes_[n].left < 0) continue;
    Children& c = children_[n];
    const int32_t kids[2] = {nodes_[n].left, nodes_[n].right};
    for (int k = 0; k < 2; ++k) {
      const Node& child = nodes_[size_t(kids[k])];
      c.bounds[k] = child.bounds;
      c.owners[k] = child.ownersUnion;
      c.minIndex[k] = child.minIndex;
      c.node[k] = kids[k];
    }
  }
  // Leaves read their proxies' boxes and masks in leaf order (one stream).
  leafBounds_.resize(order_.size());
  leafMasks_.resize(order_.size());
  for (size_t i = 0; i < order_.size(); ++i) {
    leafBounds_[i] = proxies_[size_t(order_[i])].bounds;
    leafMasks_[i] = ownerMasks_[size_t(order_[i])];
  }
}

namespace {

// Binned SAH over the centres along one axis of [first, first + count):
// returns the best split position (items with bin < split go left) and its
// cost, or cost infinity if every centre falls into one bin.
constexpr int kBins = 16;
struct SplitChoice {
  int axis = -1;
  int bin = 0;
  float cost = kInfinity;
};

}  // namespace

int32_t ProxyBvh::build(int32_t first, int32_t count, int depth,
                        const std::vector<Vec3f>& centers) {
  int32_t index = int32_t(nodes_.size());
  nodes_.push_back({});
  Box3f bounds, centerBounds;
  RankMask owners = 0;
  RankSet wideOwners;
  int32_t minIndex = std::numeric_limits<int32_t>::max();
  for (int32_t i = first; i < first + count; ++i) {
    const int32_t id = order_[i];
    const Proxy& p = proxies_[id];
    bounds.extend(p.bounds);
    centerBounds.extend(centers[size_t(id)]);
    owners |= ownerMasks_[size_t(id)];
    minIndex = std::min(minIndex, id);
    if (!narrow()) wideOwners |= p.owners;
  }
  nodes_[index].bounds = bounds;
  nodes_[index].ownersUnion = owners;
  nodes_[index].minIndex = minIndex;
  if (!narrow()) {
    if (wideUnion_.size() <= size_t(index)) wideUnion_.resize(size_t(index) + 1);
    wideUnion_[size_t(index)] = std::move(wideOwners);
  }
  auto makeLeaf = [&] {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  };
  if (count <= kLeafSize || depth > 60) return makeLeaf();

  // Binned surface-area heuristic over the centres, on all three axes: the
  // query is "the closest box along a ray", whose cost is the boxes a ray
  // enters, i.e. their surface area.
  SplitChoice best;
  const Vec3f extent = centerBounds.size();
  auto binOf = [&](int axis, int32_t id) {
    const float f = (centers[size_t(id)][axis] - centerBounds.lower[axis]) / extent[axis];
    return std::clamp(int(f * kBins), 0, kBins - 1);
  };
  for (int axis = 0; axis < 3; ++axis) {
    if (!(extent[axis] > 0)) continue;
    Box3f binBounds[kBins];
    int binCount[kBins] = {};
    for (int32_t i = first; i < first + count; ++i) {
      const int b = binOf(axis, order_[i]);
      binBounds[b].extend(proxies_[order_[i]].bounds);
      ++binCount[b];
    }
    // Sweep from the right, then from the left.
    float rightArea[kBins];
    int rightCount[kBins];
    Box3f acc;
    int n = 0;
    for (int b = kBins - 1; b > 0; --b) {
      acc.extend(binBounds[b]);
      n += binCount[b];
      rightArea[b] = acc.surfaceArea();
      rightCount[b] = n;
    }
    acc = Box3f{};
    n = 0;
    for (int b = 1; b < kBins; ++b) {
      acc.extend(binBounds[b - 1]);
      n += binCount[b - 1];
      if (n == 0 || rightCount[b] == 0) continue;
      const float cost = acc.surfaceArea() * float(n) + rightArea[b] * float(rightCount[b]);
      if (cost < best.cost) best = {axis, b, cost};
    }
  }
  int32_t mid;
  if (best.axis >= 0) {
    auto middle = std::partition(order_.begin() + first, order_.begin() + first + count,
                                 [&](int32_t id) { return binOf(best.axis, id) < best.bin; });
    mid = int32_t(middle - order_.begin());
  } else {
    // Every centre in one point: a median split by index keeps the tree balanced.
    mid = first + count / 2;
  }
  int32_t left = build(first, mid - first, depth + 1, centers);
  int32_t right = build(mid, first + count - mid, depth + 1, centers);
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
  const Vec3f inv{1 / direction.x, 1 / direction.y, 1 / direction.z};
  // Whether every proxy below node n is excluded.
  auto excludedNode = [&](int32_t n) {
    if constexpr (kMask)
      return (nodes_[size_t(n)].ownersUnion & ~ex.excluded) == 0;
    else
      return wideUnion_[size_t(n)].isSubsetOf(ex.excluded);
  };
  // Whether a subtree entered at tNode, whose least proxy index is
  // minIndex, may still hold a better proxy: its proxies are entered at
  // tNode or later, so it can only tie with the best so far at tNode, and a
  // tie goes to the lower index.
  auto mayImprove = [&](float tNode, int32_t minIndex) {
    return tNode < best.tEnter || (tNode == best.tEnter && minIndex < best.proxy);
  };
  // Closest first: children are visited nearer (then lower index) first, so
  // the best answer is found early and prunes the rest. An entry carries its
  // node's least index, so popping it reads nothing more.
  struct Entry {
    int32_t node;
    float t;
    int32_t minIndex;
  };
  Entry stack[128];
  int top = 0;
  float tRoot;
  if (excludedNode(0) || !intersectBox(nodes_[0].bounds, origin, inv, tmax, tRoot)) return best;
  stack[top++] = {0, tRoot, nodes_[0].minIndex};
  while (top > 0) {
    const Entry e = stack[--top];
    if (!mayImprove(e.t, e.minIndex)) continue;
    const Node& node = nodes_[size_t(e.node)];
    if (node.left < 0) {
      for (int32_t i = node.first; i < node.first + node.count; ++i) {
        const int32_t id = order_[size_t(i)];
        if constexpr (kMask) {
          if (leafMasks_[size_t(i)] & ex.excluded) continue;
        } else {
          if (proxies_[size_t(id)].owners.intersects(ex.excluded)) continue;
        }
        float t;
        if (!intersectBox(leafBounds_[size_t(i)], origin, inv, tmax, t)) continue;
        if (t < best.tEnter || (t == best.tEnter && id < best.proxy)) best = {id, t};
      }
      continue;
    }
    // Strictly closer, or equally close (a lower index may still win the tie).
    const float limit = std::min(tmax, nextAbove(best.tEnter));
    const Children& c = children_[size_t(e.node)];
    Entry near{-1, 0, 0}, far{-1, 0, 0};
    for (int k = 0; k < 2; ++k) {
      bool excluded;
      if constexpr (kMask)
        excluded = (c.owners[k] & ~ex.excluded) == 0;
      else
        excluded = excludedNode(c.node[k]);
      float t;
      if (excluded || !intersectBox(c.bounds[k], origin, inv, limit, t) ||
          !mayImprove(t, c.minIndex[k]))
        continue;
      const Entry entry{c.node[k], t, c.minIndex[k]};
      if (near.node < 0) {
        near = entry;
      } else if (entry.t < near.t || (entry.t == near.t && entry.minIndex < near.minIndex)) {
        far = near;
        near = entry;
      } else {
        far = entry;
      }
    }
    if (far.node >= 0) stack[top++] = far;
    if (near.node >= 0) stack[top++] = near;
  }
  return best;
}

}  // namespace ferry
