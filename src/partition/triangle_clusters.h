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

// World bounds (through `transform`) of the listed triangles' vertices.
Box3f trianglesBounds(const Mesh& mesh, const Affine3f& transform,
                      const std::vector<uint32_t>& triangles);

}  // namespace ferry
