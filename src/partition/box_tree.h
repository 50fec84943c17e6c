// A BVH over boxes answering the ray-guided partitioner's question: which
// boxes does this segment pass? (All of them, in no particular order; the
// forwarding operator's closest-proxy query is distributed/proxy_bvh.h.)
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace ferry {

class BoxTree {
 public:
  // Empty boxes are never reported.
  explicit BoxTree(const std::vector<Box3f>& boxes);

  // Indices of the boxes the segment origin + t direction, t in [0, tmax],
  // overlaps (touching counts), appended to `out`.
  void boxesAlong(Vec3f origin, Vec3f direction, float tmax, std::vector<uint32_t>& out) const;

 private:
  struct Node {
    Box3f bounds;
    uint32_t first = 0;  // leaf: boxes order_[first, first + count); inner: left child
    uint32_t count = 0;  // 0: inner node, children at first and first + 1
  };
  // Fills node `slot` with boxes order_[first, first + count) and its subtree.
  void build(uint32_t slot, uint32_t first, uint32_t count, const std::vector<Vec3f>& centres);

  std::vector<Box3f> boxes_;
  std::vector<uint32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace ferry
