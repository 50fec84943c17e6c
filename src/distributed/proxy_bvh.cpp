#include "distributed/proxy_bvh.h"

#include "core/error.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <type_traits>

#if defined(__AVX__)
#include <immintrin.h>
#endif

namespace ferry {
namespace {
constexpr int kLeafSize = 4;
// Depth to which the binary tree splits by SAH; then by halves, so any tree
// is at most kMaxSahDepth + 32 deep.
constexpr int kMaxSahDepth = 60;
constexpr int kWidth = ProxyBvh::kWidth;
// A shape tree's depth bound: full subtrees (buildShape) give at most
// ceil(log8(boxes)) levels, 11 for 2^32 boxes.
constexpr int kMaxShapeDepth = 16;

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

// Binned SAH over the centres: the best split position along one axis
// (items with bin < split go left) and its cost.
constexpr int kBins = 16;
struct SplitChoice {
  int axis = -1;
  int bin = 0;
  float cost = kInfinity;
};

}  // namespace

// Builds the binary tree (binned SAH), then collapses it into kWidth-wide nodes.
struct ProxyBvh::Builder {
  ProxyBvh& bvh;
  const std::vector<Proxy>& proxies;
  std::vector<int32_t> order;
  std::vector<Vec3f> centers;
  std::vector<BinaryNode> binary;
  std::vector<RankSet> binaryOwners;  // per binary node, only when not narrow
  std::vector<int32_t> instancedOf;   // per proxy: its instanced_ index, or -1

  int32_t build(int32_t first, int32_t count, int depth);
  int32_t collapse(int32_t binaryNode);
};

ProxyBvh::ProxyBvh(std::vector<Proxy> proxies, int ownRank, std::vector<ProxyShape> shapes,
                   std::vector<Affine3f> placements)
    : proxyCount_(proxies.size()), ownRank_(ownRank) {
  for (const Proxy& p : proxies) narrow_ = narrow_ && p.owners.fitsInMask();
  Builder b{*this, proxies, {}, {}, {}, {}, std::vector<int32_t>(proxies.size(), -1)};
  // Shapes' trees once each; an instanced proxy keeps the inverse of its
  // transform. A shape with no box (never entered) has no tree.
  std::vector<int32_t> shapeRoot(shapes.size(), -1);
  for (size_t s = 0; s < shapes.size(); ++s) {
    std::vector<Box3f>& boxes = shapes[s].boxes;
    std::erase_if(boxes, [](const Box3f& box) { return box.empty(); });
    if (!boxes.empty()) shapeRoot[s] = buildShape(boxes, 0, boxes.size(), 0);
  }
  for (size_t i = 0; i < proxies.size(); ++i) {
    const int32_t s = proxies[i].shape;
    if (s < 0) continue;
    FERRY_CHECK(size_t(s) < shapes.size());
    FERRY_CHECK(proxies[i].placement >= 0 && size_t(proxies[i].placement) < placements.size());
    b.instancedOf[i] = int32_t(instanced_.size());
    instanced_.push_back(
        {placements[size_t(proxies[i].placement)].inverse(), shapeRoot[size_t(s)]});
  }
  shapes.clear();
  placements.clear();
  // A proxy whose box is empty stands for nothing and is left out: its slab
  // distances would swap and let every ray in.
  for (size_t i = 0; i < proxies.size(); ++i)
    if (!proxies[i].bounds.empty()) b.order.push_back(int32_t(i));
  if (b.order.empty()) return;
  // The shared tree's proxies first, then those owned by ownRank alone.
  auto ownOnly = [&](const Proxy& p) {
    return ownRank >= 0 && p.owners.count() == 1 && p.owners.contains(ownRank);
  };
  const int32_t shared =
      int32_t(std::stable_partition(b.order.begin(), b.order.end(),
                                    [&](int32_t id) { return !ownOnly(proxies[size_t(id)]); }) -
              b.order.begin());
  ownOnlyCount_ = b.order.size() - size_t(shared);
  b.centers.resize(proxies.size());
  for (size_t i = 0; i < proxies.size(); ++i) b.centers[i] = proxies[i].bounds.center();
  const int32_t sharedBinary = shared > 0 ? b.build(0, shared, 0) : -1;
  const int32_t ownBinary = ownOnlyCount_ > 0 ? b.build(shared, int32_t(ownOnlyCount_), 0) : -1;
  // A wide node per binary inner node at most (plus a root that is a leaf,
  // per tree): reserved, so the nodes are never copied as they grow (only
  // the pages written become resident).
  nodes_.reserve(b.binary.size() / 2 + 2);
  if (!narrow_) slotOwners_.reserve(nodes_.capacity() * kWidth);
  if (sharedBinary >= 0) sharedRoot_ = b.collapse(sharedBinary);
  if (ownBinary >= 0) ownRoot_ = b.collapse(ownBinary);
}

size_t ProxyBvh::bytes() const {
  size_t owners = 0;
  for (const RankSet& s : slotOwners_) owners += sizeof(RankSet) + (s.wordCount() - 1) * 8;
  return nodes_.size() * sizeof(Node) + owners + instanced_.size() * sizeof(Instanced) +
         shapeNodes_.size() * sizeof(ShapeNode);
}

// A node over at most kWidth boxes holds them; more are cut into at most
// kWidth groups of s boxes each (one group may have fewer), s the least
// power of kWidth with kWidth * s >= count, by cuts at multiples of s in the
// order of the box centres along the widest axis. Every subtree is then as
// full as it can be: nodes hold kWidth boxes but for one per level, about
// 30 bytes per box (docs/partitioning.md, "Shapes by size"). The tree is at
// most ceil(log8(count)) deep, which bounds the query's stack.
int32_t ProxyBvh::buildShape(std::vector<Box3f>& boxes, size_t first, size_t count, int depth) {
  FERRY_CHECK_LT(depth, kMaxShapeDepth);
  struct Range {
    size_t first, count;
  };
  size_t groupSize = 1;
  while (groupSize * size_t(kWidth) < count) groupSize *= size_t(kWidth);
  std::vector<Range> groups;
  std::vector<Range> pending{{first, count}};
  while (!pending.empty()) {
    const Range g = pending.back();
    pending.pop_back();
    if (g.count <= groupSize) {
      groups.push_back(g);
      continue;
    }
    Box3f centres;
    for (size_t i = g.first; i < g.first + g.count; ++i) centres.extend(boxes[i].center());
    const Vec3f size = centres.size();
    const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
    const size_t chunks = (g.count + groupSize - 1) / groupSize;
    const size_t left = chunks / 2 * groupSize;
    auto begin = boxes.begin() + std::ptrdiff_t(g.first);
    std::nth_element(
        begin, begin + std::ptrdiff_t(left), begin + std::ptrdiff_t(g.count),
        [axis](const Box3f& a, const Box3f& b) { return a.center()[axis] < b.center()[axis]; });
    pending.push_back({g.first + left, g.count - left});
    pending.push_back({g.first, left});
  }
  FERRY_CHECK_LE(groups.size(), size_t(kWidth));
  const int32_t index = int32_t(shapeNodes_.size());
  shapeNodes_.emplace_back();
  for (size_t k = 0; k < groups.size(); ++k) {
    Box3f box;
    for (size_t i = groups[k].first; i < groups[k].first + groups[k].count; ++i)
      box.extend(boxes[i]);
    int32_t child = -1;
    if (groups[k].count > 1) child = buildShape(boxes, groups[k].first, groups[k].count, depth + 1);
    ShapeNode& node = shapeNodes_[size_t(index)];  // looked up again: the child appended
    for (int a = 0; a < 3; ++a) node.lower[a][k] = box.lower[a], node.upper[a][k] = box.upper[a];
    node.child[k] = child;
    node.usedSlots |= 1u << k;
    if (child < 0) node.boxSlots |= 1u << k;
  }
  ShapeNode& node = shapeNodes_[size_t(index)];
  for (size_t k = groups.size(); k < size_t(kWidth); ++k) {
    for (int a = 0; a < 3; ++a) node.lower[a][k] = kInfinity, node.upper[a][k] = -kInfinity;
    node.child[k] = -1;
  }
  return index;
}

int32_t ProxyBvh::Builder::build(int32_t first, int32_t count, int depth) {
  int32_t index = int32_t(binary.size());
  binary.push_back({});
  Box3f bounds, centerBounds;
  RankMask owners = 0;
  RankSet wideOwners;
  int32_t minIndex = std::numeric_limits<int32_t>::max();
  for (int32_t i = first; i < first + count; ++i) {
    const int32_t id = order[size_t(i)];
    bounds.extend(proxies[size_t(id)].bounds);
    centerBounds.extend(centers[size_t(id)]);
    owners |= proxies[size_t(id)].owners.mask();
    minIndex = std::min(minIndex, id);
    if (!bvh.narrow_) wideOwners |= proxies[size_t(id)].owners;
  }
  binary[size_t(index)].bounds = bounds;
  binary[size_t(index)].ownersUnion = owners;
  binary[size_t(index)].minIndex = minIndex;
  if (!bvh.narrow_) {
    binaryOwners.resize(binary.size());
    binaryOwners[size_t(index)] = std::move(wideOwners);
  }
  if (count <= kLeafSize) {
    binary[size_t(index)].first = first;
    binary[size_t(index)].count = count;
    return index;
  }
  // Below kMaxSahDepth the split is a median by index: a leaf never holds
  // more proxies than a node has slots, and the depth stays bounded (the
  // query's stack) whatever the SAH did above.
  const bool sah = depth <= kMaxSahDepth;

  // Binned surface-area heuristic over the centres, on all three axes: the
  // query is "the closest box along a ray", whose cost is the boxes a ray
  // enters, i.e. their surface area.
  SplitChoice best;
  const Vec3f extent = centerBounds.size();
  auto binOf = [&](int axis, int32_t id) {
    const float f = (centers[size_t(id)][axis] - centerBounds.lower[axis]) / extent[axis];
    return std::clamp(int(f * kBins), 0, kBins - 1);
  };
  for (int axis = 0; axis < 3 && sah; ++axis) {
    if (!(extent[axis] > 0)) continue;
    Box3f binBounds[kBins];
    int binCount[kBins] = {};
    for (int32_t i = first; i < first + count; ++i) {
      const int b = binOf(axis, order[size_t(i)]);
      binBounds[b].extend(proxies[size_t(order[size_t(i)])].bounds);
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
    auto middle = std::partition(order.begin() + first, order.begin() + first + count,
                                 [&](int32_t id) { return binOf(best.axis, id) < best.bin; });
    mid = int32_t(middle - order.begin());
  } else {
    // Every centre in one point, or deeper than kMaxSahDepth: a median split
    // by index keeps the tree balanced.
    mid = first + count / 2;
  }
  int32_t left = build(first, mid - first, depth + 1);
  int32_t right = build(mid, first + count - mid, depth + 1);
  binary[size_t(index)].left = left;
  binary[size_t(index)].right = right;
  return index;
}

// A wide node's children: starting from the binary node's own children, the
// child with the largest surface area is opened (an inner node into its two
// children, a leaf into its proxies) while the result still fits in kWidth
// slots, so a node covers the top few binary levels below it.
int32_t ProxyBvh::Builder::collapse(int32_t binaryNode) {
  struct Item {
    int32_t binary;  // >= 0: a binary node; else ~proxy
  };
  auto opened = [&](int32_t b, std::vector<Item>& out) {
    const BinaryNode& n = binary[size_t(b)];
    if (n.left >= 0) {
      out.push_back({n.left});
      out.push_back({n.right});
    } else {
      for (int32_t i = n.first; i < n.first + n.count; ++i) out.push_back({~order[size_t(i)]});
    }
  };
  auto openCount = [&](int32_t b) {
    const BinaryNode& n = binary[size_t(b)];
    return n.left >= 0 ? 2 : n.count;
  };
  std::vector<Item> items;
  opened(binaryNode, items);
  for (;;) {
    int pick = -1;
    float area = -1;
    for (size_t k = 0; k < items.size(); ++k) {
      const int32_t b = items[k].binary;
      if (b < 0 || int(items.size()) - 1 + openCount(b) > kWidth) continue;
      const float a = binary[size_t(b)].bounds.surfaceArea();
      if (a > area) area = a, pick = int(k);
    }
    if (pick < 0) break;
    const int32_t b = items[size_t(pick)].binary;
    items.erase(items.begin() + pick);
    opened(b, items);
  }

  const int32_t index = int32_t(bvh.nodes_.size());
  bvh.nodes_.emplace_back();
  if (!bvh.narrow_) bvh.slotOwners_.resize(bvh.nodes_.size() * kWidth);
  {
    Node& node = bvh.nodes_.back();
    for (int k = 0; k < kWidth; ++k) {
      for (int a = 0; a < 3; ++a) node.lower[a][k] = kInfinity, node.upper[a][k] = -kInfinity;
      node.owners[k] = 0;
      node.minIndex[k] = std::numeric_limits<int32_t>::max();
      node.child[k] = 0;
    }
  }
  for (size_t k = 0; k < items.size(); ++k) {
    const int32_t b = items[k].binary;
    Box3f box;
    RankMask owners;
    int32_t minIndex, child;
    if (b < 0) {
      const int32_t id = ~b;
      box = proxies[size_t(id)].bounds;
      owners = proxies[size_t(id)].owners.mask();
      minIndex = id;
      child = instancedOf[size_t(id)];
      bvh.nodes_[size_t(index)].proxySlots |= 1u << k;
      if (!bvh.narrow_) bvh.slotOwners_[size_t(index) * kWidth + k] = proxies[size_t(id)].owners;
    } else {
      box = binary[size_t(b)].bounds;
      owners = binary[size_t(b)].ownersUnion;
      minIndex = binary[size_t(b)].minIndex;
      child = collapse(b);  // appends nodes: `node` is looked up again below
      if (!bvh.narrow_) bvh.slotOwners_[size_t(index) * kWidth + k] = binaryOwners[size_t(b)];
    }
    Node& node = bvh.nodes_[size_t(index)];
    for (int a = 0; a < 3; ++a) node.lower[a][k] = box.lower[a], node.upper[a][k] = box.upper[a];
    node.owners[k] = owners;
    node.minIndex[k] = minIndex;
    node.child[k] = child;
  }
  return index;
}

namespace {
// The two ways of asking which slots' owners are excluded. A node's slot is
// skipped when every owner below it is excluded; a proxy's when any is.
struct MaskExclusion {
  RankMask excluded;
};
struct SetExclusion {
  const RankSet& excluded;
};

using Floats = float __attribute__((vector_size(4 * kWidth)));
using Ints = int32_t __attribute__((vector_size(4 * kWidth)));

inline Floats load(const float* p) {
  Floats v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline Floats splat(float x) {
  Floats v;
  for (int k = 0; k < kWidth; ++k) v[k] = x;
  return v;
}
// Bit k set where lane k of a comparison's result is true (all ones).
inline uint32_t bits(Ints m) {
#if defined(__AVX__)
  static_assert(kWidth == 8);
  __m256 v;
  std::memcpy(&v, &m, sizeof v);
  return uint32_t(_mm256_movemask_ps(v));
#else
  uint32_t out = 0;
  for (int k = 0; k < kWidth; ++k) out |= uint32_t(m[k] != 0) << k;
  return out;
#endif
}

// The slots of a node (its boxes lower[axis][slot], upper[axis][slot]) the
// ray (origin o, 1 / direction inv, both splat) enters before `limit`, and
// each slot's entry distance in t0. Every slot at once, exactly as
// intersectBox (Box3f::clipRay) computes it lane by lane, so that answers do
// not depend on the width: per axis the slab distances, swapped when
// reversed, an axis skipped where one is NaN (the origin on a slab plane of
// a flat direction), entry = max (from 0), exit = min (from limit), a hit
// when entry <= exit and entry < limit.
[[gnu::always_inline]] inline uint32_t enteredSlots(const float (&lower)[3][kWidth],
                                                    const float (&upper)[3][kWidth],
                                                    const Floats (&o)[3], const Floats (&inv)[3],
                                                    float limit, Floats& t0) {
  t0 = splat(0.0f);
  Floats t1 = splat(limit);
  for (int a = 0; a < 3; ++a) {
    const Floats lo = (load(lower[a]) - o[a]) * inv[a];
    const Floats hi = (load(upper[a]) - o[a]) * inv[a];
    const Ints swap = lo > hi;
    const Floats near = swap ? hi : lo, far = swap ? lo : hi;
    const Ints ordered = near <= far;
    t0 = (ordered & (t0 < near)) ? near : t0;
    t1 = (ordered & (far < t1)) ? far : t1;
  }
  return bits((t0 <= t1) & (t0 < splat(limit)));
}
}  // namespace

float ProxyBvh::enterInstanced(const Instanced& p, Vec3f origin, Vec3f direction,
                               float limit) const {
  if (p.root < 0) return kInfinity;
  // Affine: the ray's parameter is the same in both spaces.
  const Vec3f o = p.toObject.transformPoint(origin);
  const Vec3f d = p.toObject.transformVector(direction);
  const Floats ov[3] = {splat(o.x), splat(o.y), splat(o.z)};
  const Floats invV[3] = {splat(1 / d.x), splat(1 / d.y), splat(1 / d.z)};
  // A box's entry distance is never less than its node's (the node's box
  // holds it, and the slab distances are monotone in the bounds), so a node
  // entered no closer than the best box so far is skipped. The least entry
  // does not depend on the order the boxes are tested in.
  float first = kInfinity;
  int32_t stack[kMaxShapeDepth * kWidth];
  int top = 0;
  stack[top++] = p.root;
  while (top > 0) {
    const ShapeNode& node = shapeNodes_[size_t(stack[--top])];
    Floats t0;
    const uint32_t entered =
        enteredSlots(node.lower, node.upper, ov, invV, std::min(limit, first), t0) & node.usedSlots;
    for (uint32_t b = entered & node.boxSlots; b != 0; b &= b - 1)
      first = std::min(first, t0[std::countr_zero(b)]);
    for (uint32_t s = entered & ~node.boxSlots; s != 0; s &= s - 1) {
      const int k = std::countr_zero(s);
      if (t0[k] < first) stack[top++] = node.child[k];
    }
  }
  return first;
}

float ProxyBvh::coneClearance(Vec3f eye, const std::array<Vec3f, 4>& corners,
                              RankMask excluded) const {
  if (!narrow()) return 0;
  // Planes through the eye, normals inwards: the cone's four sides, and the
  // plane across its axis (its directions are within 90 degrees of the axis).
  const Vec3f axis = corners[0] + corners[1] + corners[2] + corners[3];
  Vec3f normal[5];
  normal[4] = normalize(axis);
  for (int i = 0; i < 4; ++i) {
    if (!(dot(corners[size_t(i)], normal[4]) > 0)) return 0;  // not a narrow cone: no bound
    Vec3f n = cross(corners[size_t(i)], corners[size_t((i + 1) % 4)]);
    const float len = length(n);
    if (!(len > 0) || !std::isfinite(len)) return 0;  // a degenerate cone: no bound
    n = n * (1 / len);
    normal[i] = dot(n, axis) < 0 ? -n : n;
  }
  // Whether `box` may meet the widened cone: some corner of it is inside
  // every side, by the margin's angle (its sine) times the corner's distance.
  auto meetsCone = [&](Vec3f lo, Vec3f hi) {
    const Vec3f a = lo - eye, b = hi - eye;
    const Vec3f far{std::max(std::abs(a.x), std::abs(b.x)), std::max(std::abs(a.y), std::abs(b.y)),
                    std::max(std::abs(a.z), std::abs(b.z))};
    const float slack = kConeMargin * length(far);
    for (const Vec3f& n : normal) {
      const float most = std::max(n.x * a.x, n.x * b.x) + std::max(n.y * a.y, n.y * b.y) +
                         std::max(n.z * a.z, n.z * b.z);
      if (most < -slack) return false;
    }
    return true;
  };
  // Distance from the eye to a box: a unit ray enters it no nearer.
  auto distanceTo = [&](Vec3f lo, Vec3f hi) {
    return length(max(max(lo - eye, eye - hi), Vec3f(0)));
  };
  bool ownSearched = ownRoot_ >= 0 && !((excluded >> ownRank_) & 1u);
  float best = kInfinity;
  int32_t stack[(kMaxSahDepth + 34) * kWidth + kWidth];  // as search()'s
  int top = 0;
  for (int32_t root : {sharedRoot_, ownSearched ? ownRoot_ : -1})
    if (root >= 0) stack[top++] = root;
  while (top > 0) {
    const Node& node = nodes_[size_t(stack[--top])];
    for (int k = 0; k < kWidth; ++k) {
      const bool proxy = (node.proxySlots >> k) & 1u;
      const bool eligible =
          proxy ? (node.owners[k] & excluded) == 0 : (node.owners[k] & ~excluded) != 0;
      if (!eligible) continue;
      const Vec3f lo{node.lower[0][k], node.lower[1][k], node.lower[2][k]};
      const Vec3f hi{node.upper[0][k], node.upper[1][k], node.upper[2][k]};
      if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) continue;  // never entered
      const float d = distanceTo(lo, hi);
      if (!(d < best) || !meetsCone(lo, hi)) continue;
      // (An instanced proxy's slot holds its boxes' world box: a lower bound too.)
      if (proxy)
        best = d;
      else
        stack[top++] = node.child[k];
    }
  }
  return best;
}

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
  bool ownSearched = ownRoot_ >= 0;
  if (ownSearched) {
    if constexpr (std::is_same_v<Excluded, MaskExclusion>)
      ownSearched = !((ex.excluded >> ownRank_) & 1u);  // narrow: ownRank_ < 64
    else
      ownSearched = !ex.excluded.contains(ownRank_);
  }
  // Both trees at once (below): searched one after the other, the first
  // tree's answer is often far and bounds the second badly.
  Hit best;
  search(sharedRoot_, ownSearched ? ownRoot_ : -1, origin, direction, tmax, ex, best);
  return best;
}

// The closest-first search of the trees at `rootA` and `rootB` (-1: none),
// improving on `best`. The two roots' children start the search together,
// sorted as one node's would be, so that two trees cost about what one does.
template <typename Excluded>
void ProxyBvh::search(int32_t rootA, int32_t rootB, Vec3f origin, Vec3f direction, float tmax,
                      const Excluded& ex, Hit& best) const {
  constexpr bool kMask = std::is_same_v<Excluded, MaskExclusion>;
  const Vec3f inv{1 / direction.x, 1 / direction.y, 1 / direction.z};
  const Floats o[3] = {splat(origin.x), splat(origin.y), splat(origin.z)};
  const Floats invV[3] = {splat(inv.x), splat(inv.y), splat(inv.z)};
  // The slots of node n that may hold an answer, by owners alone.
  auto eligible = [&](int32_t n) {
    const Node& node = nodes_[size_t(n)];
    uint32_t out = 0;
    for (int k = 0; k < kWidth; ++k) {
      bool skip;
      const bool proxy = (node.proxySlots >> k) & 1u;
      if constexpr (kMask) {
        skip = proxy ? (node.owners[k] & ex.excluded) != 0 : (node.owners[k] & ~ex.excluded) == 0;
      } else {
        const RankSet& owners = slotOwners_[size_t(n) * kWidth + size_t(k)];
        skip = proxy ? owners.intersects(ex.excluded)
                     : owners.isSubsetOf(ex.excluded);  // an unused slot: empty, a subset
      }
      out |= uint32_t(!skip) << k;
    }
    return out;
  };
  // A subtree entered at tNode whose least proxy index is minIndex may still
  // hold a better proxy: its proxies are entered at tNode or later, so it can
  // only tie with the best so far at tNode, and a tie goes to the lower index.
  auto mayImprove = [&](float tNode, int32_t minIndex) {
    return tNode < best.tEnter || (tNode == best.tEnter && minIndex < best.proxy);
  };
  // Closest first: a node's children are pushed farthest first, so the best
  // answer is found early and prunes the rest. An entry carries its node's
  // least index, so popping it reads nothing more.
  struct Entry {
    int32_t node;
    float t;
    int32_t minIndex;
  };
  Entry stack[(kMaxSahDepth + 34) * kWidth + kWidth];  // kWidth - 1 siblings wait per level
  int top = 0;
  // Tests node n's slots: proxies may improve `best`; subtrees that may hold
  // a better one go into sub[0, count), nearest (then lowest index) last.
  auto expand = [&](int32_t n, Entry* sub, int& count) {
    const Node& node = nodes_[size_t(n)];
    // Strictly closer, or equally close (a lower index may still win the tie).
    const float limit = std::min(tmax, nextAbove(best.tEnter));
    Floats t0;
    uint32_t candidates = enteredSlots(node.lower, node.upper, o, invV, limit, t0);
    if (candidates == 0) return;  // owners are read only for slots the ray enters
    candidates &= eligible(n);
    if (candidates == 0) return;
    // Proxies first: they may lower the bar for this node's subtrees.
    for (uint32_t p = candidates & node.proxySlots; p != 0; p &= p - 1) {
      const int k = std::countr_zero(p);
      float t = t0[k];
      const int32_t id = node.minIndex[k];
      if (!(t < best.tEnter || (t == best.tEnter && id < best.proxy))) continue;
      // An instanced proxy's slot holds its boxes' world box: entered there
      // or later (a lower bound, as a node's box is for its subtree).
      if (node.child[k] >= 0)
        t = enterInstanced(instanced_[size_t(node.child[k])], origin, direction, limit);
      if (t < best.tEnter || (t == best.tEnter && id < best.proxy)) {
        if constexpr (kMask)
          best = {id, t, node.owners[k], nullptr};
        else
          best = {id, t, 0, &slotOwners_[size_t(n) * kWidth + size_t(k)]};
      }
    }
    for (uint32_t s = candidates & ~node.proxySlots; s != 0; s &= s - 1) {
      const int k = std::countr_zero(s);
      const Entry entry{node.child[k], t0[k], node.minIndex[k]};
      if (!mayImprove(entry.t, entry.minIndex)) continue;
      int j = count++;
      for (; j > 0 && (sub[j - 1].t < entry.t ||
                       (sub[j - 1].t == entry.t && sub[j - 1].minIndex < entry.minIndex));
           --j)
        sub[j] = sub[j - 1];
      sub[j] = entry;
    }
  };
  // Children are sorted straight onto the stack (copying them there from a
  // small array became a libc memmove call per node).
  for (int32_t root : {rootA, rootB})
    if (root >= 0) expand(root, stack, top);
  while (top > 0) {
    const Entry e = stack[--top];
    if (!mayImprove(e.t, e.minIndex)) continue;
    int count = 0;
    expand(e.node, stack + top, count);
    top += count;
  }
}

}  // namespace ferry
