#include "partition/triangle_clusters.h"

#include <algorithm>
#include <queue>

#include "scene/scene.h"

namespace ferry {

std::vector<std::vector<uint32_t>> clusterTriangles(const Mesh& mesh, const Affine3f& transform,
                                                    int maxClusters) {
  const size_t n = mesh.indices.size();
  std::vector<std::vector<uint32_t>> out;
  if (n == 0) return out;
  std::vector<Vec3f> world(mesh.positions.size());
  for (size_t v = 0; v < world.size(); ++v) world[v] = transform.transformPoint(mesh.positions[v]);
  std::vector<Vec3f> centroid(n);
  for (size_t t = 0; t < n; ++t) {
    const Vec3i& tri = mesh.indices[t];
    centroid[t] = (world[tri.x] + world[tri.y] + world[tri.z]) * (1.0f / 3.0f);
  }
  std::vector<uint32_t> order(n);
  for (size_t t = 0; t < n; ++t) order[t] = uint32_t(t);

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
    Box3f bounds;
    for (size_t i = r.begin; i < r.end; ++i) bounds.extend(centroid[order[i]]);
    const int axis = bounds.longestAxis();
    const size_t mid = r.begin + (r.end - r.begin) / 2;
    // A strict total order (ties by index), so the two halves are the same sets
    // whatever the standard library's nth_element does.
    std::nth_element(order.begin() + long(r.begin), order.begin() + long(mid),
                     order.begin() + long(r.end), [&](uint32_t a, uint32_t b) {
                       float ca = centroid[a][axis], cb = centroid[b][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    queue.push({r.begin, mid});
    queue.push({mid, r.end});
  }
  while (!queue.empty()) {
    done.push_back(queue.top());
    queue.pop();
  }
  for (const Range& r : done) {
    std::vector<uint32_t> c(order.begin() + long(r.begin), order.begin() + long(r.end));
    std::sort(c.begin(), c.end());
    out.push_back(std::move(c));
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return a.front() < b.front(); });
  return out;
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
