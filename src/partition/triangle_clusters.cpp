#include "partition/triangle_clusters.h"

#include <algorithm>
#include <queue>

#include "scene/scene.h"

namespace ferry {

namespace {

// Vertices and triangle centroids after `transform`, and the triangles'
// indices in order.
struct Centroids {
  std::vector<Vec3f> world;
  std::vector<Vec3f> centroid;
  std::vector<uint32_t> order;
};

Centroids centroidsOf(const Mesh& mesh, const Affine3f& transform) {
  const size_t n = mesh.indices.size();
  Centroids c;
  std::vector<Vec3f>& world = c.world;
  world.resize(mesh.positions.size());
  for (size_t v = 0; v < world.size(); ++v) world[v] = transform.transformPoint(mesh.positions[v]);
  c.centroid.resize(n);
  for (size_t t = 0; t < n; ++t) {
    const Vec3i& tri = mesh.indices[t];
    c.centroid[t] = (world[tri.x] + world[tri.y] + world[tri.z]) * (1.0f / 3.0f);
  }
  c.order.resize(n);
  for (size_t t = 0; t < n; ++t) c.order[t] = uint32_t(t);
  return c;
}

// One build step: reorders c.order[begin, end) so that its two halves are
// the triangles below and above the median centroid along the longest axis
// of their centroid bounds, and returns where the second half starts. The
// halves are the same sets whatever order the range was in (a strict total
// order, ties by index, whatever the standard library's nth_element does),
// so clusterTriangles and clusterTree make the same clusters.
size_t splitAtMedian(Centroids& c, size_t begin, size_t end) {
  Box3f bounds;
  for (size_t i = begin; i < end; ++i) bounds.extend(c.centroid[c.order[i]]);
  const int axis = bounds.longestAxis();
  const size_t mid = begin + (end - begin) / 2;
  std::nth_element(c.order.begin() + long(begin), c.order.begin() + long(mid),
                   c.order.begin() + long(end), [&](uint32_t a, uint32_t b) {
                     float ca = c.centroid[a][axis], cb = c.centroid[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  return mid;
}

}  // namespace

std::vector<std::vector<uint32_t>> clusterTriangles(const Mesh& mesh, const Affine3f& transform,
                                                    int maxClusters) {
  const size_t n = mesh.indices.size();
  std::vector<std::vector<uint32_t>> out;
  if (n == 0) return out;
  Centroids c = centroidsOf(mesh, transform);

  struct Range {
    size_t begin, end;
  };
  // Largest cluster first; among equals, the one that starts first.
  auto smaller = [](const Range& a, const Range& b) {
    size_t na = a.end - a.begin, nb = b.end - b.begin;
    return na < nb || (na == nb && a.begin > b.begin);
  };
  std::priority_queue<Range, std::vector<Range>, decltype(smaller)> queue(smaller);
  std::vector<Range> done;
  queue.push({0, n});
  const size_t target = size_t(std::max(1, maxClusters));
  while (!queue.empty() && queue.size() + done.size() < target) {
    Range r = queue.top();
    queue.pop();
    if (r.end - r.begin < 2) {
      done.push_back(r);
      continue;
    }
    const size_t mid = splitAtMedian(c, r.begin, r.end);
    queue.push({r.begin, mid});
    queue.push({mid, r.end});
  }
  while (!queue.empty()) {
    done.push_back(queue.top());
    queue.pop();
  }
  for (const Range& r : done) {
    std::vector<uint32_t> cluster(c.order.begin() + long(r.begin), c.order.begin() + long(r.end));
    std::sort(cluster.begin(), cluster.end());
    out.push_back(std::move(cluster));
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.front() < b.front(); });
  return out;
}

ClusterTree clusterTree(const Mesh& mesh, const Affine3f& transform, size_t leafSize) {
  ClusterTree tree;
  const size_t n = mesh.indices.size();
  if (n == 0) return tree;
  Centroids c = centroidsOf(mesh, transform);
  leafSize = std::max<size_t>(leafSize, 1);
  tree.nodes.reserve(2 * ((n + leafSize - 1) / leafSize));
  tree.nodes.push_back({Box3f(), 0, uint32_t(n)});
  // Depth first; children are appended, so a node's index is below theirs.
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const uint32_t k = stack.back();
    stack.pop_back();
    const ClusterTree::Node node = tree.nodes[k];
    if (node.count <= leafSize) continue;
    const size_t mid = splitAtMedian(c, node.first, node.first + node.count);
    tree.nodes[k].left = int32_t(tree.nodes.size());
    tree.nodes.push_back({Box3f(), node.first, uint32_t(mid - node.first)});
    tree.nodes[k].right = int32_t(tree.nodes.size());
    tree.nodes.push_back({Box3f(), uint32_t(mid), uint32_t(node.first + node.count - mid)});
    stack.push_back(uint32_t(tree.nodes[k].right));
    stack.push_back(uint32_t(tree.nodes[k].left));
  }
  // Bounds bottom up, from the triangles' vertices at the leaves (exactly
  // trianglesBounds of the node's triangles: min and max are exact).
  for (size_t k = tree.nodes.size(); k-- > 0;) {
    ClusterTree::Node& node = tree.nodes[k];
    if (node.left < 0) {
      for (uint32_t i = node.first; i < node.first + node.count; ++i) {
        const Vec3i& tri = mesh.indices[c.order[i]];
        for (int v = 0; v < 3; ++v) node.bounds.extend(c.world[tri[v]]);
      }
    } else {
      node.bounds = tree.nodes[size_t(node.left)].bounds;
      node.bounds.extend(tree.nodes[size_t(node.right)].bounds);
    }
  }
  tree.triangles = std::move(c.order);
  return tree;
}

Box3f trianglesBounds(const Mesh& mesh, const Affine3f& transform,
                      const std::vector<uint32_t>& triangles) {
  Box3f b;
  for (uint32_t t : triangles) {
    const Vec3i& tri = mesh.indices[t];
    for (int k = 0; k < 3; ++k) b.extend(transform.transformPoint(mesh.positions[tri[k]]));
  }
  return b;
}

}  // namespace ferry
