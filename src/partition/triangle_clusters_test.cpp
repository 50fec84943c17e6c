#include "partition/triangle_clusters.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "scene/scene.h"

namespace ferry {
namespace {

// Scattered small triangles, some with equal centroid coordinates (ties).
Mesh triangleSoup(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-10.0f, 10.0f);
  Mesh mesh;
  for (int t = 0; t < count; ++t) {
    Vec3f c{u(rng), u(rng), t % 5 == 0 ? 1.0f : u(rng)};
    const int32_t base = int32_t(mesh.positions.size());
    mesh.positions.push_back(c);
    mesh.positions.push_back(c + Vec3f{0.3f, 0, 0});
    mesh.positions.push_back(c + Vec3f{0, 0.2f, 0.1f});
    mesh.indices.push_back({base, base + 1, base + 2});
  }
  return mesh;
}

std::vector<uint32_t> sortedTriangles(const ClusterTree& tree, const ClusterTree::Node& node) {
  std::vector<uint32_t> out(tree.triangles.begin() + node.first,
                            tree.triangles.begin() + node.first + node.count);
  std::sort(out.begin(), out.end());
  return out;
}

bool sameBox(const Box3f& a, const Box3f& b) {
  for (int k = 0; k < 3; ++k)
    if (a.lower[k] != b.lower[k] || a.upper[k] != b.upper[k]) return false;
  return true;
}

// The cover check relies on this: whatever number of clusters braiding asked
// for, each cluster is a node of the tree, with bit-identical bounds.
TEST(ClusterTree, EveryBraidedClusterIsANodeWithTheSameBounds) {
  const Mesh mesh = triangleSoup(1000, 7);
  const Affine3f transforms[] = {Affine3f::identity(), Affine3f::translate({5, -2, 1}) *
                                                           Affine3f::rotate({1, 2, 3}, 0.7f) *
                                                           Affine3f::scale({2, 1, 0.5f})};
  for (const Affine3f& transform : transforms) {
    const ClusterTree tree = clusterTree(mesh, transform, 1);  // down to single triangles
    for (int clusters : {1, 2, 3, 4, 7, 64, 300}) {
      for (const std::vector<uint32_t>& cluster : clusterTriangles(mesh, transform, clusters)) {
        bool found = false;
        for (const ClusterTree::Node& node : tree.nodes) {
          if (node.count != cluster.size() || sortedTriangles(tree, node) != cluster) continue;
          EXPECT_TRUE(sameBox(node.bounds, trianglesBounds(mesh, transform, cluster)));
          found = true;
          break;
        }
        EXPECT_TRUE(found) << clusters << " clusters: one of " << cluster.size()
                           << " triangles is not a node";
      }
    }
  }
}

TEST(ClusterTree, LeavesPartitionTheTrianglesAndChildrenSplitTheirParent) {
  const Mesh mesh = triangleSoup(333, 3);
  const ClusterTree tree = clusterTree(mesh, Affine3f::identity(), 16);
  ASSERT_FALSE(tree.nodes.empty());
  EXPECT_EQ(tree.nodes[0].count, 333u);
  std::vector<int> seen(333, 0);
  for (const ClusterTree::Node& node : tree.nodes) {
    if (node.left < 0) {
      EXPECT_LE(node.count, 16u);
      for (uint32_t t : sortedTriangles(tree, node)) ++seen[t];
      continue;
    }
    const ClusterTree::Node& l = tree.nodes[size_t(node.left)];
    const ClusterTree::Node& r = tree.nodes[size_t(node.right)];
    EXPECT_EQ(l.first, node.first);
    EXPECT_EQ(l.count + r.count, node.count);
    EXPECT_EQ(r.first, node.first + l.count);
    Box3f both = l.bounds;
    both.extend(r.bounds);
    EXPECT_TRUE(sameBox(both, node.bounds));
  }
  for (int count : seen) EXPECT_EQ(count, 1);
  EXPECT_TRUE(clusterTree(Mesh{}, Affine3f::identity(), 16).nodes.empty());
}

}  // namespace
}  // namespace ferry
