// A BVH over proxies, on every rank, answering the forwarding operator's
// question: along this ray, before tmax, which is the closest proxy none of
// whose owners the ray has visited? Ties in entry distance go to the lower
// proxy index, so every rank answers identically.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/math.h"
#include "partition/partition.h"

namespace ferry {

class ProxyBvh {
 public:
  ProxyBvh() = default;
  // The tree keeps what a query needs (each proxy's box and owners in its
  // node's slot) and nothing else: `proxies` is consumed, so a rank holds
  // every proxy once. With `ownRank` >= 0, the proxies owned by that rank
  // alone go in a tree of their own, which a query excluding `ownRank` (every
  // forwarding decision of that rank) never enters; a query that does not
  // (which rank owns a camera path, replay walks) searches both. The answers
  // are those of one tree. `shapes` and `placements`: what instanced proxies
  // refer to (Proxy::shape, Proxy::placement), consumed too. Why:
  // docs/memory.md, "Each proxy held once"; docs/data-parallel.md, "Each
  // rank's own proxies apart".
  explicit ProxyBvh(std::vector<Proxy> proxies, int ownRank = -1,
                    std::vector<ProxyShape> shapes = {}, std::vector<Affine3f> placements = {});

  struct Hit {
    int32_t proxy = -1;
    float tEnter = kInfinity;
    // The proxy's owners: the mask when every owner is below rank 64 (the
    // tree is narrow), else the set, which the tree holds.
    RankMask ownerMask = 0;
    const RankSet* ownerSet = nullptr;
    bool found() const { return proxy >= 0; }
    RankSet owners() const { return ownerSet ? *ownerSet : RankSet::fromMask(ownerMask); }
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
  bool narrow() const { return narrow_; }

  // A lower bound on where any ray from `eye` whose direction lies in the
  // cone spanned by `corners` (four directions, in order around it, as a
  // pixel's corners are; widened by kConeMargin radians) enters a proxy whose
  // owners do not intersect `excluded`: closest(eye, d, tmax, excluded) finds
  // nothing for such a unit d and a tmax at most this. Infinity when no such
  // proxy meets the cone; 0 (no bound) when the tree is not narrow. What
  // lets a camera ray's forwarding decision go without a query
  // (docs/data-parallel.md, "Camera rays that need no query").
  float coneClearance(Vec3f eye, const std::array<Vec3f, 4>& corners, RankMask excluded) const;
  // The cone's widening: a few times the direction error of a path's stored
  // (octahedral) direction, so that a stored camera ray stays inside.
  static constexpr float kConeMargin = 2e-4f;

  // Proxies given, with those of empty boxes (never entered).
  size_t proxyCount() const { return proxyCount_; }
  // Of those, instanced ones (a transform each, their shapes' boxes held once).
  size_t instancedCount() const { return instanced_.size(); }
  size_t nodeCount() const { return nodes_.size(); }
  // What the tree holds, in bytes (nodes, owner sets above 64 ranks,
  // instanced proxies' transforms and their shapes' trees).
  size_t bytes() const;
  // Proxies in the tree a query excluding the own rank never enters.
  size_t ownOnlyCount() const { return ownOnlyCount_; }

  // Children per node. The query tests a node's children together, 8 lanes
  // of one vector operation per slab (AVX with x86-64-v3), each lane exactly
  // the scalar box test (docs/architecture.md, "A wide proxy tree with
  // scalar answers").
  static constexpr int kWidth = 8;

 private:
  template <typename Excluded>
  Hit closestImpl(Vec3f origin, Vec3f direction, float tmax, const Excluded& excluded) const;
  template <typename Excluded>
  void search(int32_t rootA, int32_t rootB, Vec3f origin, Vec3f direction, float tmax,
              const Excluded& excluded, Hit& best) const;

  // Up to kWidth children, each a node or a single proxy, structure of
  // arrays so that one load fills a lane per child. An unused slot has no
  // owners and is never entered.
  struct alignas(32) Node {
    float lower[3][kWidth];
    float upper[3][kWidth];
    RankMask owners[kWidth];   // a node: the union below it; a proxy: its owners (narrow)
    int32_t minIndex[kWidth];  // least proxy index below (a proxy: its index): prunes ties
    int32_t child[kWidth];     // a node's index; a proxy: its instanced_ index, or -1
    uint32_t proxySlots = 0;   // bit k: slot k holds a proxy
  };
  // The binary SAH tree the wide one is collapsed from (construction only).
  struct BinaryNode {
    Box3f bounds;
    RankMask ownersUnion = 0;
    int32_t left = -1, right = -1;  // children; -1 in a leaf
    int32_t first = 0, count = 0;   // leaf range in order
    int32_t minIndex = 0;
  };
  struct Builder;

  // An instanced proxy: the ray taken into its object's space, and the
  // tree of its shape's boxes (shapeNodes_[root]).
  struct Instanced {
    Affine3f toObject;
    int32_t root = -1;
  };
  // A shape's boxes, in its object's space, under a kWidth-wide tree of
  // their own, built once per shape: a shape of many boxes (64 per mesh of
  // a 13-mesh tree model is 832) costs a few node tests per query, not one
  // test per box, so instanced proxies can be as fine as the braiding makes
  // them (docs/partitioning.md, "Instanced proxies").
  struct ShapeNode {
    float lower[3][kWidth];
    float upper[3][kWidth];
    int32_t child[kWidth];  // a node slot: the node's index
    uint32_t usedSlots = 0;
    uint32_t boxSlots = 0;  // bit k: slot k is one of the shape's boxes
  };
  // Appends the tree over boxes[first, first + count) (reordered); returns its root.
  int32_t buildShape(std::vector<Box3f>& boxes, size_t first, size_t count, int depth);
  // Where the ray enters the instanced proxy's boxes before `limit`, or
  // infinity: the least entry distance over the boxes, as testing each box
  // in turn gives it.
  float enterInstanced(const Instanced& p, Vec3f origin, Vec3f direction, float limit) const;

  size_t proxyCount_ = 0;
  bool narrow_ = true;
  std::vector<Node> nodes_;
  int32_t sharedRoot_ = -1;  // every proxy but those owned by ownRank_ alone
  int32_t ownRoot_ = -1;     // those, when ownRank_ >= 0
  int ownRank_ = -1;
  size_t ownOnlyCount_ = 0;
  std::vector<RankSet> slotOwners_;  // per node and slot, only when not narrow
  std::vector<Instanced> instanced_;
  std::vector<ShapeNode> shapeNodes_;
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
