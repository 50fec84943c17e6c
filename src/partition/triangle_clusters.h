// Spatially coherent groups of a mesh's triangles, made by BVH build steps
// (the cluster with the most triangles is split at the median centroid along
// the longest axis of its centroid bounds). Used to cut large meshes into
// pieces (the `best` partitioner) and to cover a mesh by several tight
// proxies instead of one loose box (braiding, `object-proxies`).
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace ferry {

struct Mesh;

// Up to `maxClusters` clusters (fewer if the mesh has fewer triangles); each
// lists triangle indices in ascending order, and clusters are ordered by
// their first triangle. Deterministic. Centroids are taken after `transform`.
std::vector<std::vector<uint32_t>> clusterTriangles(const Mesh& mesh, const Affine3f& transform,
                                                    int maxClusters);

// The whole binary tree of those build steps, split down to clusters of at
// most `leafSize` triangles. Every cluster clusterTriangles makes (with the
// same transform, any maxClusters) is one of its nodes, with the same
// bounds, so a check that proxies cover a mesh can go down it until a node's
// box lies in proxies (Partition::checkCovers) instead of testing triangle by
// triangle. Bounds are of the nodes' triangles' vertices after `transform`.
struct ClusterTree {
  struct Node {
    Box3f bounds;
    uint32_t first = 0, count = 0;  // triangles[first, first + count)
    int32_t left = -1, right = -1;  // children, or -1 for a leaf
  };
  std::vector<Node> nodes;          // nodes[0] is the root (none for an empty mesh)
  std::vector<uint32_t> triangles;  // triangle indices, each node's contiguous
};
ClusterTree clusterTree(const Mesh& mesh, const Affine3f& transform, size_t leafSize);

// World bounds (through `transform`) of the listed triangles' vertices.
Box3f trianglesBounds(const Mesh& mesh, const Affine3f& transform,
                      const std::vector<uint32_t>& triangles);

}  // namespace ferry
