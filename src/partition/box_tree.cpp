#include "partition/box_tree.h"

#include <algorithm>

namespace ferry {
namespace {

constexpr uint32_t kLeafSize = 4;

// Whether the segment [0, tmax] meets `box` (touching counts).
bool segmentMeets(const Box3f& box, Vec3f origin, Vec3f inverse, float tmax) {
  float t0 = 0, t1 = tmax;
  return box.clipRay(origin, inverse, t0, t1);
}

}  // namespace

BoxTree::BoxTree(const std::vector<Box3f>& boxes) : boxes_(boxes) {
  std::vector<Vec3f> centres(boxes.size());
  for (uint32_t i = 0; i < boxes.size(); ++i) {
    if (boxes[i].empty()) continue;
    order_.push_back(i);
    centres[i] = boxes[i].center();
  }
  if (!order_.empty()) {
    nodes_.reserve(4 * order_.size() / kLeafSize + 2);
    nodes_.emplace_back();
    build(0, 0, uint32_t(order_.size()), centres);
  }
}

void BoxTree::build(uint32_t slot, uint32_t first, uint32_t count,
                    const std::vector<Vec3f>& centres) {
  Box3f bounds, centreBounds;
  for (uint32_t k = first; k < first + count; ++k) {
    bounds.extend(boxes_[order_[k]]);
    centreBounds.extend(centres[order_[k]]);
  }
  nodes_[slot].bounds = bounds;
  if (count <= kLeafSize) {
    nodes_[slot].first = first;
    nodes_[slot].count = count;
    return;
  }
  // Median of the centres on the longest axis (ties by index: deterministic).
  const int axis = centreBounds.longestAxis();
  const uint32_t half = count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + first + half,
                   order_.begin() + first + count, [&](uint32_t a, uint32_t b) {
                     return centres[a][axis] < centres[b][axis] ||
                            (centres[a][axis] == centres[b][axis] && a < b);
                   });
  const uint32_t children = uint32_t(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[slot].first = children;
  nodes_[slot].count = 0;
  build(children, first, half, centres);
  build(children + 1, first + half, count - half, centres);
}

void BoxTree::boxesAlong(Vec3f origin, Vec3f direction, float tmax,
                         std::vector<uint32_t>& out) const {
  if (nodes_.empty()) return;
  const Vec3f inverse(1.0f / direction.x, 1.0f / direction.y, 1.0f / direction.z);
  uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!segmentMeets(node.bounds, origin, inverse, tmax)) continue;
    if (node.count > 0) {
      for (uint32_t k = node.first; k < node.first + node.count; ++k)
        if (segmentMeets(boxes_[order_[k]], origin, inverse, tmax)) out.push_back(order_[k]);
    } else {
      stack[top++] = node.first;
      stack[top++] = node.first + 1;
    }
  }
}

}  // namespace ferry
