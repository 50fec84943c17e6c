// The trace backend `ferry` renders with: Embree structures for the content
// this rank owns. Two-level: one Embree scene per instanced object, placed by
// instance geometries in a top-level scene; with Instancing::Shared the
// meshes of an object placed once, untransformed, sit in the top-level scene
// itself (trace_backend.h). Queues are traced with Embree's stream API
// (rtcIntersect1M / rtcOccluded1M) in batches of 256 rays, written once in
// Embree's ray layout (docs/performance.md for why). Embree's headers and
// types stay in the .cpp.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "trace/trace_backend.h"

namespace ferry {

struct Scene;

// Builds Embree structures over `ownedInstances` of `scene` (all instances
// when empty). The scene is shared with Embree, not copied, and must outlive
// the backend; a mesh whose positions lack one element of spare capacity
// (Embree reads 16 bytes at the last vertex; Mesh::hasVertexSlack) is traced
// from a padded copy the backend keeps and counts in bytes(). Throws
// TraceError when Embree fails.
std::unique_ptr<TraceBackend> makeEmbreeBackend(const Scene& scene,
                                                std::span<const int32_t> ownedInstances = {},
                                                Instancing instancing = Instancing::Shared);

}  // namespace ferry
