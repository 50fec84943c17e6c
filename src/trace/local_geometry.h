// The rank-local tracer: Embree structures for the content this rank owns.
// Two-level: one Embree scene per instanced object, placed by instance
// geometries in a top-level scene (instancing is never flattened: an object's
// triangles exist once however often it is placed). An object this rank
// places exactly once, untransformed, instances nothing: by default
// (Instancing::Shared) its meshes go straight into the top-level scene, as a
// production renderer keeps unique geometry, which saves every ray an
// instance transform and a second BVH root (15 % of Embree's own tutorial
// frame on the bunny, docs/performance.md). Instancing::Always gives every
// object an instance level. Alpha cut-outs are applied
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

// A batch of queries written once, in the layout Embree's stream API reads
// and answers in place (RTCRayHit; the .cpp checks every offset), so a caller
// that has its rays in another form (the compact path) converts each ray once
// and reads each answer where Embree wrote it: no intermediate TraceRay or
// TraceHit arrays. Closest-hit and occlusion queries go to two lists; each
// query keeps the caller's index. Traced on the calling thread by
// LocalGeometry::trace.
class RayBatch {
 public:
  static constexpr size_t kCapacity = 256;

  void clear() { closestCount_ = occludedCount_ = 0; }
  bool full() const { return closestCount_ + occludedCount_ == kCapacity; }
  void addClosest(uint32_t index, Vec3f origin, Vec3f direction, float tmax, float tnear = 0) {
    closestIndex_[closestCount_] = index;
    closest_[closestCount_++].set(origin, direction, tnear, tmax);
  }
  void addOccluded(uint32_t index, Vec3f origin, Vec3f direction, float tmax, float tnear = 0) {
    occludedIndex_[occludedCount_] = index;
    occluded_[occludedCount_++].set(origin, direction, tnear, tmax);
  }

  size_t closestCount() const { return closestCount_; }
  size_t occludedCount() const { return occludedCount_; }
  uint32_t closestIndex(size_t k) const { return closestIndex_[k]; }
  uint32_t occludedIndex(size_t k) const { return occludedIndex_[k]; }
  // Answers, after LocalGeometry::trace.
  bool hitFound(size_t k) const { return closest_[k].geomID != kNoGeometry; }
  float hitDistance(size_t k) const { return closest_[k].tfar; }
  TraceHit hit(size_t k) const {
    const EmbreeRay& r = closest_[k];
    if (r.geomID == kNoGeometry) return {};
    return {r.tfar, int32_t(r.instID), int32_t(r.geomID), r.primID, r.u, r.v};
  }
  bool isOccluded(size_t k) const { return occluded_[k].tfar < 0; }  // Embree sets tfar = -inf

 private:
  friend class LocalGeometry;
  static constexpr uint32_t kNoGeometry = 0xffffffffu;  // RTC_INVALID_GEOMETRY_ID
  // RTCRayHit, field for field (one instance level).
  struct alignas(16) EmbreeRay {
    float orgX, orgY, orgZ, tnear;
    float dirX, dirY, dirZ, time;
    float tfar;
    uint32_t mask, id, flags;
    float ngX, ngY, ngZ, u, v;
    uint32_t primID, geomID, instID;
    void set(Vec3f o, Vec3f d, float tmin, float tmax) {
      orgX = o.x, orgY = o.y, orgZ = o.z, tnear = tmin;
      dirX = d.x, dirY = d.y, dirZ = d.z, time = 0;
      tfar = tmax, mask = 0xffffffffu, id = 0, flags = 0;
      geomID = kNoGeometry, instID = kNoGeometry;
    }
  };
  EmbreeRay closest_[kCapacity];
  EmbreeRay occluded_[kCapacity];  // only the ray part is used
  uint32_t closestIndex_[kCapacity], occludedIndex_[kCapacity];
  size_t closestCount_ = 0, occludedCount_ = 0;
};

// Which objects get an instance level (see the top of this file).
enum class Instancing : uint8_t {
  Shared,  // objects placed more than once, or transformed; unique geometry at the top level
  Always   // every object, even one placed once
};

class LocalGeometry {
 public:
  // Builds Embree structures over `ownedInstances` of `scene` (all instances
  // when empty). `threads` bounds Embree's build threads (0: all).
  // The scene is shared with Embree, not copied, and must outlive this object;
  // its vertex arrays may get one element of spare capacity (Embree reads 16
  // bytes at the last vertex).
  explicit LocalGeometry(Scene& scene, std::span<const int32_t> ownedInstances = {},
                         Instancing instancing = Instancing::Shared);
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
  // Traces both lists of `batch` on the calling thread (rtcIntersect1M, rtcOccluded1M).
  void trace(RayBatch& batch) const;

  const Scene& scene() const { return scene_; }
  Box3f bounds() const;
  // Bytes Embree holds now and at its peak, from its memory-monitor callback.
  int64_t embreeBytes() const;
  int64_t embreePeakBytes() const;
  // Objects and instances actually built on this rank (an object placed at
  // the top level counts as both), and of those how many are at the top level.
  uint64_t builtObjectCount() const;
  uint64_t builtInstanceCount() const;
  uint64_t topLevelObjectCount() const;

 private:
  struct Impl;
  Scene& scene_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ferry
