// The scene transformation done before partitioning, so that every unit a
// partitioner deals out is an instance (and Partition::instanceOwners stays
// the one contract with the renderer):
//   - Zellmann et al.: each mesh of a single-instance object with several
//     meshes becomes its own single-instance object (same transform);
//   - `best`: meshes costing more than a threshold are cut into spatially
//     coherent pieces (triangle clusters), and so are geometries of other
//     kinds that can be cut (Shape::subset: curves, by median splits of
//     their segments), each piece its own object placed by the same
//     instances, so one large object can be spread over several ranks.
// The rendered image does not change: the same triangles (same vertex data,
// same order within each piece), the same materials and transforms. Light
// sampling is built from the scene before this transformation (the order of
// emissive triangles is part of the random-number mapping).
#pragma once

#include <cstdint>
#include <vector>

namespace ferry {

struct Scene;

struct SceneSplitOptions {
  bool breakSingleInstanceObjects = true;
  // Meshes whose memory estimate exceeds this are cut into about
  // ceil(cost / maxPieceBytes) pieces (at most kMaxPiecesPerMesh); 0: none cut.
  uint64_t maxPieceBytes = 0;
};

constexpr int kMaxPiecesPerMesh = 1024;

struct SceneSplitReport {
  uint64_t objectsBroken = 0;  // single-instance objects split into their meshes
  uint64_t meshesCut = 0;      // meshes and geometries cut
  uint64_t piecesMade = 0;     // pieces of the cut meshes and geometries, all together
  // For each instance of the new scene, the instance of the old scene it came from.
  std::vector<int32_t> originalInstance;
};

// Rewrites `scene` in place (meshes are moved, not copied, except the pieces
// of cut meshes, made one mesh at a time). Mesh, object and instance order is
// kept: a broken or cut instance is replaced by consecutive instances.
SceneSplitReport splitForPartitioning(Scene& scene, const SceneSplitOptions& options);

}  // namespace ferry
