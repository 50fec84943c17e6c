// The rank-local tracer: Embree structures for the content this rank owns.
// Two-level: one Embree scene per object, placed by instance geometries in a
// top-level scene (instancing is never flattened). Alpha cut-outs are applied
// in Embree intersection/occlusion filters. Embree's headers stay in the .cpp
// so a second backend touches only this folder.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/math.h"

namespace ferry {

struct Scene;

struct TraceRay {
  Vec3f origin;
  Vec3f direction;
  float tnear = 0;
  float tmax = kInfinity;
};

struct TraceHit {
  float t = kInfinity;
  int32_t instance = -1;   // index into Scene::instances
  int32_t meshSlot = -1;   // index into the instance's Object::meshes
  uint32_t primitive = 0;  // triangle within the mesh
  float u = 0, v = 0;      // barycentrics of vertices 1 and 2

  bool valid() const { return instance >= 0; }
};

// What traceBatch asks about one ray.
enum class TraceQuery : uint8_t {
  None,     // nothing: the ray is skipped, its answer left unset
  Closest,  // the closest hit (rtcIntersect)
  Occluded  // whether anything is hit (rtcOccluded)
};

class LocalGeometry {
 public:
  // Builds Embree structures over `ownedInstances` of `scene` (all instances
  // when empty). `threads` bounds Embree's build threads (0: all).
  // The scene is shared with Embree, not copied, and must outlive this object;
  // its vertex arrays may get one element of spare capacity (Embree reads 16
  // bytes at the last vertex).
  explicit LocalGeometry(Scene& scene, std::span<const int32_t> ownedInstances = {});
  ~LocalGeometry();
  LocalGeometry(const LocalGeometry&) = delete;
  LocalGeometry& operator=(const LocalGeometry&) = delete;

  TraceHit intersect(const TraceRay& ray) const;
  bool occluded(const TraceRay& ray) const;
  // Batched queries; implemented with Embree's stream API (rtcIntersect1M /
  // rtcOccluded1M), see docs/performance.md for why.
  void intersect(std::span<const TraceRay> rays, std::span<TraceHit> hits) const;
  void occluded(std::span<const TraceRay> rays, std::span<uint8_t> occluded) const;
  // A mixed batch, traced on the calling thread (callers parallelize over
  // batches; a few hundred rays each keeps the arrays in cache): ray i is
  // skipped, or its closest hit goes to hits[i], or its occlusion to
  // occluded[i]. Entries of other kinds are left as they are. Same Embree
  // stream queries as the parallel calls above, so the same answers.
  void traceBatch(std::span<const TraceRay> rays, std::span<const TraceQuery> queries,
                  std::span<TraceHit> hits, std::span<uint8_t> occluded) const;

  const Scene& scene() const { return scene_; }
  Box3f bounds() const;
  // Bytes Embree holds now and at its peak, from its memory-monitor callback.
  int64_t embreeBytes() const;
  int64_t embreePeakBytes() const;
  // Objects and instances actually built on this rank.
  uint64_t builtObjectCount() const;
  uint64_t builtInstanceCount() const;

 private:
  struct Impl;
  Scene& scene_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ferry
