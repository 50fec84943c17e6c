#include "trace/embree_backend.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/parallel_for_each.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "core/error.h"
#include "scene/scene.h"
#include "trace/alpha_cutout.h"
#include "trace/queue_trace.h"

namespace ferry {
namespace {

// A batch of queries written once, in the layout Embree's stream API reads
// and answers in place (RTCRayHit, every offset checked below), so a path is
// converted once and each answer read where Embree wrote it: no intermediate
// TraceRay or TraceHit arrays. Closest-hit and occlusion queries go to two
// lists; each query keeps the caller's index. (The Batch of queue_trace.h.)
class RayBatch {
 public:
  static constexpr size_t kCapacity = 256;  // in cache, and large enough for the stream API

  void clear() {
    closestCount_ = occludedCount_ = 0;
    work_ = {};
  }
  ShapeWork shapeWork() const { return work_; }
  void addClosest(uint32_t index, Vec3f origin, Vec3f direction, float tmax, float time = 0) {
    closestIndex_[closestCount_] = index;
    closest_[closestCount_++].set(origin, direction, 0, tmax, time);
  }
  void addOccluded(uint32_t index, Vec3f origin, Vec3f direction, float tmax, float time = 0) {
    occludedIndex_[occludedCount_] = index;
    occluded_[occludedCount_++].set(origin, direction, 0, tmax, time);
  }

  size_t closestCount() const { return closestCount_; }
  size_t occludedCount() const { return occludedCount_; }
  uint32_t closestIndex(size_t k) const { return closestIndex_[k]; }
  uint32_t occludedIndex(size_t k) const { return occludedIndex_[k]; }
  // Answers, after EmbreeBackend::traceBatch.
  bool hitFound(size_t k) const { return closest_[k].geomID != kNoGeometry; }
  float hitDistance(size_t k) const { return closest_[k].tfar; }
  TraceHit hit(size_t k) const {
    const EmbreeRay& r = closest_[k];
    if (r.geomID == kNoGeometry) return {};
    return {r.tfar, int32_t(r.instID), int32_t(r.geomID), r.primID, r.u, r.v, r.time};
  }
  bool isOccluded(size_t k) const { return occluded_[k].tfar < 0; }  // Embree sets tfar = -inf

 private:
  friend class EmbreeBackend;
  static constexpr uint32_t kNoGeometry = RTC_INVALID_GEOMETRY_ID;
  // RTCRayHit, field for field (one instance level), with the setter the
  // queries need.
  struct alignas(16) EmbreeRay {
    float orgX, orgY, orgZ, tnear;
    float dirX, dirY, dirZ, time;
    float tfar;
    uint32_t mask, id, flags;
    float ngX, ngY, ngZ, u, v;
    uint32_t primID, geomID, instID;
    void set(Vec3f o, Vec3f d, float tmin, float tmax, float when) {
      orgX = o.x, orgY = o.y, orgZ = o.z, tnear = tmin;
      dirX = d.x, dirY = d.y, dirZ = d.z, time = when;
      tfar = tmax, mask = 0xffffffffu, id = 0, flags = 0;
      geomID = kNoGeometry, instID = kNoGeometry;
    }
    // A query Embree skips (tnear > tfar), answered with no hit and not occluded.
    void setDead() { set({0, 0, 0}, {0, 0, 1}, 1, 0, 0); }
    void hashRay() { id = alphaRayHash({orgX, orgY, orgZ}, {dirX, dirY, dirZ}); }
  };
  EmbreeRay closest_[kCapacity];
  EmbreeRay occluded_[kCapacity];  // only the ray part is used
  uint32_t closestIndex_[kCapacity], occludedIndex_[kCapacity];
  size_t closestCount_ = 0, occludedCount_ = 0;
  ShapeWork work_;
};

#define FERRY_SAME_OFFSET(ours, theirs)                                             \
  static_assert(offsetof(RayBatch::EmbreeRay, ours) == offsetof(RTCRayHit, theirs), \
                #ours " must sit where RTCRayHit has " #theirs);

// A mesh's cut-out with the scene's instances, whose transforms place a hit
// through an instance in the world (solid alpha textures are functions of it).
struct EmbreeCutout {
  AlphaCutout cutout;
  const std::vector<Instance>* instances;
};

// Rejects hits in alpha cut-outs: the intersect filter for paths, the
// occluded filter for shadow rays (the cut-out says which it cuts). A ray's
// id holds its alphaRayHash when the scene has stochastic cut-outs.
void alphaFilter(const RTCFilterFunctionNArguments* args) {
  const auto* filter = static_cast<const EmbreeCutout*>(args->geometryUserPtr);
  // Instance geometries are attached under their instance's id; a top-level
  // mesh has none and is untransformed.
  const unsigned instance = args->context->instID[0];
  const Affine3f* toWorld =
      instance == RTC_INVALID_GEOMETRY_ID ? nullptr : &(*filter->instances)[instance].transform;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    float u = RTCHitN_u(args->hit, args->N, i);
    float v = RTCHitN_v(args->hit, args->N, i);
    uint32_t prim = RTCHitN_primID(args->hit, args->N, i);
    if (filter->cutout.isHole(prim, u, v, toWorld, RTCRayN_id(args->ray, args->N, i)))
      args->valid[i] = 0;
  }
}

// Bytes now and at the peak: Embree's (its memory-monitor callback) and the
// backend's own padded vertex copies.
struct MemoryCounters {
  std::atomic<int64_t> now{0}, peak{0};
  void add(int64_t bytes) {
    int64_t current = now.fetch_add(bytes) + bytes;
    int64_t high = peak.load();
    while (current > high && !peak.compare_exchange_weak(high, current)) {
    }
  }
};

bool memoryMonitor(void* user, ssize_t bytes, bool /*post*/) {
  static_cast<MemoryCounters*>(user)->add(bytes);
  return true;
}

const char* errorName(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE:
      return "no error";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
    default:
      return "unknown error";
  }
}

// Errors Embree reports through its callback, from whichever thread called
// it (a worker inside a parallel trace, Embree's own build threads). They
// cannot be thrown through Embree's C code, so the first one is kept and the
// backend call that was running throws it on the calling thread when it
// returns (every call checks; one relaxed load when nothing failed).
class ErrorLog {
 public:
  void record(RTCError code, const char* message) {
    std::lock_guard lock(mutex_);
    if (failed_.load(std::memory_order_relaxed)) return;
    first_ = fmt::format("error {} ({}){}{}", int(code), errorName(code), message ? ": " : "",
                         message ? message : "");
    failed_.store(true, std::memory_order_release);
  }
  void throwIfFailed(const char* what) const {
    if (!failed_.load(std::memory_order_acquire)) return;
    std::lock_guard lock(mutex_);
    throw TraceError(fmt::format("Embree failed while {}: {}", what, first_));
  }

 private:
  mutable std::mutex mutex_;
  std::atomic<bool> failed_{false};
  std::string first_;
};

void errorCallback(void* user, RTCError code, const char* message) {
  if (code != RTC_ERROR_NONE) static_cast<ErrorLog*>(user)->record(code, message);
}

// Every query's context: Embree's, and where the shapes' crossings add
// their work (a batch's; null for single rays). Embree hands callbacks the
// context it was given, so a callback reads the extension.
struct TraceContext {
  RTCIntersectContext embree;
  ShapeWork* work = nullptr;
  explicit TraceContext(ShapeWork* w = nullptr) : work(w) { rtcInitIntersectContext(&embree); }
};

// A geometry of another kind (scene/shape.h) as an Embree user geometry:
// Embree builds its BVH over the primitives' boxes and asks the shape for
// each crossing.
// Embree's primitive id is primitive * piecesPerPrimitive() + piece.
void shapeBounds(const RTCBoundsFunctionArguments* args) {
  const Shape& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  const uint32_t pieces = shape.piecesPerPrimitive();
  const Box3f b = shape.pieceBounds(args->primID / pieces, args->primID % pieces);
  RTCBounds* out = args->bounds_o;
  out->lower_x = b.lower.x;
  out->lower_y = b.lower.y;
  out->lower_z = b.lower.z;
  out->upper_x = b.upper.x;
  out->upper_y = b.upper.y;
  out->upper_z = b.upper.z;
}

// Ray i of a stream's packet against the piece Embree names: its origin,
// direction and t range.
template <typename Args>
bool shapeCrossing(const Args* args, RTCRayN* ray, unsigned i, float& t, Vec2f& uv) {
  const unsigned n = args->N;
  const Vec3f origin{RTCRayN_org_x(ray, n, i), RTCRayN_org_y(ray, n, i), RTCRayN_org_z(ray, n, i)};
  const Vec3f direction{RTCRayN_dir_x(ray, n, i), RTCRayN_dir_y(ray, n, i),
                        RTCRayN_dir_z(ray, n, i)};
  const Shape& shape = *static_cast<const Shape*>(args->geometryUserPtr);
  ShapeWork* work = reinterpret_cast<const TraceContext*>(args->context)->work;
  ShapeWork unused;
  const uint32_t pieces = shape.piecesPerPrimitive();
  return shape.intersectPiece(args->primID / pieces, args->primID % pieces, origin, direction,
                              RTCRayN_tnear(ray, n, i), RTCRayN_tfar(ray, n, i), t, uv,
                              work ? *work : unused);
}

void shapeIntersect(const RTCIntersectFunctionNArguments* args) {
  RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, args->N);
  RTCHitN* hit = RTCRayHitN_HitN(args->rayhit, args->N);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    float t;
    Vec2f uv;
    if (!shapeCrossing(args, ray, i, t, uv)) continue;
    const unsigned n = args->N;
    RTCRayN_tfar(ray, n, i) = t;
    RTCHitN_Ng_x(hit, n, i) = 0;  // (shading rebuilds the normal from the shape)
    RTCHitN_Ng_y(hit, n, i) = 0;
    RTCHitN_Ng_z(hit, n, i) = 1;
    RTCHitN_u(hit, n, i) = uv.x;
    RTCHitN_v(hit, n, i) = uv.y;
    RTCHitN_primID(hit, n, i) =
        args->primID / static_cast<const Shape*>(args->geometryUserPtr)->piecesPerPrimitive();
    RTCHitN_geomID(hit, n, i) = args->geomID;
    RTCHitN_instID(hit, n, i, 0) = args->context->instID[0];
  }
}

void shapeOccluded(const RTCOccludedFunctionNArguments* args) {
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    float t;
    Vec2f uv;
    if (shapeCrossing(args, args->ray, i, t, uv))
      RTCRayN_tfar(args->ray, args->N, i) = -std::numeric_limits<float>::infinity();
  }
}

RTCRayHit toEmbree(const TraceRay& r) {
  RTCRayHit rh{};
  rh.ray.org_x = r.origin.x;
  rh.ray.org_y = r.origin.y;
  rh.ray.org_z = r.origin.z;
  rh.ray.dir_x = r.direction.x;
  rh.ray.dir_y = r.direction.y;
  rh.ray.dir_z = r.direction.z;
  rh.ray.tnear = r.tnear;
  rh.ray.tfar = r.tmax;
  rh.ray.time = r.time;
  rh.ray.mask = 0xffffffffu;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

// Re-trace margin (docs/architecture.md): Embree accepts a hit only somewhat
// inside tfar, with an error that scales with the coordinates, not with t,
// so the re-trace searches past the recorded distance by a margin of both
// kinds; nothing closer than the recorded hit
// exists, so the closest hit found is the same one.
TraceRay retraceQuery(const RetraceRay& r) {
  const Vec3f o = r.origin;
  const float scale = std::max({std::abs(o.x), std::abs(o.y), std::abs(o.z), 1.0f});
  return {o, r.direction, 0, r.tmax * 1.001f + 1e-4f * scale, r.time};
}

// Embree's handles, released when the backend goes (or its build throws).
struct EmbreeHandles {
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  std::unordered_map<int32_t, RTCScene> objectScenes;

  EmbreeHandles() = default;
  EmbreeHandles(const EmbreeHandles&) = delete;
  EmbreeHandles& operator=(const EmbreeHandles&) = delete;
  ~EmbreeHandles() {
    if (top) rtcReleaseScene(top);
    for (auto& [id, s] : objectScenes)
      if (s) rtcReleaseScene(s);
    if (device) rtcReleaseDevice(device);
  }
};

class EmbreeBackend final : public TraceBackend {
 public:
  EmbreeBackend(const Scene& scene, std::span<const int32_t> ownedInstances, Instancing instancing);

  TraceCounts trace(PathQueue<Path8>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  TraceCounts trace(PathQueue<Path64>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  TraceCounts trace(PathQueue<PathReplay>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  TraceCounts trace(PathQueue<PathProbe>& paths, int rank, std::span<const uint64_t> owners,
                    std::span<TraceHit> kept, const PathTimes& times) const override {
    return traceQueue(paths, rank, owners, kept, times);
  }
  void retrace(std::span<const RetraceRay> rays, std::span<TraceHit> hits) const override;
  TraceHit intersect(const TraceRay& ray) const override;
  bool occluded(const TraceRay& ray) const override;
  Box3f bounds() const override;
  BackendBytes bytes() const override { return {memory_.now.load(), memory_.peak.load()}; }
  BuiltCounts built() const override {
    return {embree_.objectScenes.size() + topLevelObjects_, instanceCount_, topLevelObjects_};
  }

 private:
  template <typename Path>
  TraceCounts traceQueue(PathQueue<Path>& paths, int rank, std::span<const uint64_t> owners,
                         std::span<TraceHit> kept, const PathTimes& times) const {
    TraceCounts counts = traceQueueInBatches<RayBatch>(
        paths, rank, owners, kept, times, [this](RayBatch& batch) { traceBatch(batch); });
    errors_.throwIfFailed("tracing a wavefront");
    return counts;
  }
  // Traces both lists of `batch` on the calling thread (rtcIntersect1M, rtcOccluded1M).
  void traceBatch(RayBatch& batch) const;
  // A hit on a top-level mesh has no instance id and its top-level geometry
  // id: rewrite both to what a hit through an instance would have said.
  void nameHit(uint32_t& geomID, uint32_t& instID) const {
    if (geomID == RTC_INVALID_GEOMETRY_ID || instID != RTC_INVALID_GEOMETRY_ID) return;
    const TopLevelMesh& m = topLevelMeshes_[geomID - topLevelBase_];
    instID = uint32_t(m.instance);
    geomID = uint32_t(m.slot);
  }
  TraceHit hitOf(const RTCRayHit& rh) const;
  // The vertex array Embree reads for `mesh`: the scene's own when it has a
  // spare element, else a padded copy kept here.
  const Vec3f* sharedPositions(const Mesh& mesh);
  // The coverage `cutout`'s tests may read, built on first use (null for a
  // solid texture). Called with buildMutex_ held.
  const AlphaCoverage* coverage(const AlphaCutout& cutout);
  // Embree geometries for the meshes and geometries of `object`, each attached to `target`
  // by the id idForSlot(slot) returns.
  template <typename IdForSlot>
  void attachMeshes(const Object& object, RTCScene target, const IdForSlot& idForSlot);
  // The scene of an object placed through an instance (built by buildObjectScenes).
  RTCScene objectScene(int32_t objectId) const;
  // Builds a scene for each of `objects`, concurrently: a rank's instanced
  // objects are many and mostly small, too small for Embree's own parallel
  // build to keep the threads busy one object at a time.
  void buildObjectScenes(const std::vector<int32_t>& objects);
  void checkBuild(const char* what);

  const Scene& scene_;
  MemoryCounters memory_;
  ErrorLog errors_;
  // Meshes attached straight to the top-level scene, by top-level geometry id
  // minus topLevelBase_: the instance and mesh slot a hit on them names.
  struct TopLevelMesh {
    int32_t instance, slot;
  };
  std::vector<TopLevelMesh> topLevelMeshes_;
  uint32_t topLevelBase_ = 0;
  uint64_t topLevelObjects_ = 0;
  uint64_t instanceCount_ = 0;
  std::vector<std::unique_ptr<EmbreeCutout>> cutouts_;
  // One per image texture and alpha test the cut-outs use.
  std::map<std::tuple<const Texture*, float, AlphaTest>, std::unique_ptr<AlphaCoverage>> coverages_;
  bool hashesRays_ = false;  // a cut-out is stochastic: rays carry their alphaRayHash as id
  std::unordered_map<const Mesh*, std::vector<Vec3f>> paddedPositions_;
  std::mutex buildMutex_;  // guards the four above while objects build concurrently
  // Last, so released first: Embree calls the counters and reads the buffers above until then.
  EmbreeHandles embree_;
};

EmbreeBackend::EmbreeBackend(const Scene& scene, std::span<const int32_t> ownedInstances,
                             Instancing instancing)
    : scene_(scene) {
  embree_.device = rtcNewDevice(nullptr);
  if (!embree_.device)
    throw TraceError(fmt::format("could not create an Embree device (error {})",
                                 int(rtcGetDeviceError(nullptr))));
  rtcSetDeviceErrorFunction(embree_.device, errorCallback, &errors_);
  rtcSetDeviceMemoryMonitorFunction(embree_.device, memoryMonitor, &memory_);

  std::vector<int32_t> all;
  if (ownedInstances.empty()) {
    all.resize(scene.instances.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = int32_t(i);
    ownedInstances = all;
  }

  // Objects placed once on this rank, untransformed: their meshes go to the top level.
  std::unordered_map<int32_t, int> placements;
  for (int32_t instanceId : ownedInstances) ++placements[scene.instances[instanceId].object];
  auto atTopLevel = [&](const Instance& inst) {
    return instancing == Instancing::Shared && placements[inst.object] == 1 &&
           inst.transform.isIdentity() && !inst.motion;
  };
  topLevelBase_ = uint32_t(scene.instances.size());  // instances keep their own ids below

  // Every object placed through an instance gets its own scene, all built
  // before the top level, concurrently (buildObjectScenes).
  std::vector<int32_t> instancedObjects;
  for (int32_t instanceId : ownedInstances) {
    const Instance& inst = scene.instances[instanceId];
    if (!atTopLevel(inst) && embree_.objectScenes.emplace(inst.object, nullptr).second)
      instancedObjects.push_back(inst.object);
  }
  buildObjectScenes(instancedObjects);

  embree_.top = rtcNewScene(embree_.device);
  for (int32_t instanceId : ownedInstances) {
    const Instance& inst = scene.instances[instanceId];
    if (atTopLevel(inst)) {
      attachMeshes(scene.objects[inst.object], embree_.top, [&](int32_t slot) {
        topLevelMeshes_.push_back({instanceId, slot});
        return unsigned(topLevelBase_ + topLevelMeshes_.size() - 1);
      });
      ++topLevelObjects_;
      ++instanceCount_;
      continue;
    }
    RTCGeometry g = rtcNewGeometry(embree_.device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, objectScene(inst.object));
    if (inst.motion) {  // its keys, spread evenly over the ray's time [0, 1]
      const std::vector<MotionKey>& keys = inst.motion->keys();
      rtcSetGeometryTimeStepCount(g, unsigned(keys.size()));
      for (size_t k = 0; k < keys.size(); ++k) {
        const MotionKey& key = keys[k];
        RTCQuaternionDecomposition q;
        rtcInitQuaternionDecomposition(&q);
        rtcQuaternionDecompositionSetQuaternion(&q, key.rotation[3], key.rotation[0],
                                                key.rotation[1], key.rotation[2]);
        rtcQuaternionDecompositionSetScale(&q, key.scaleX, key.scaleY, key.scaleZ);
        rtcQuaternionDecompositionSetSkew(&q, key.skewXY, key.skewXZ, key.skewYZ);
        rtcQuaternionDecompositionSetShift(&q, key.shift.x, key.shift.y, key.shift.z);
        rtcQuaternionDecompositionSetTranslation(&q, key.translation.x, key.translation.y,
                                                 key.translation.z);
        rtcSetGeometryTransformQuaternion(g, unsigned(k), &q);
      }
    } else {
      float xfm[12];
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) xfm[r * 4 + c] = inst.transform.l[r][c];
        xfm[r * 4 + 3] = inst.transform.t[r];
      }
      rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(embree_.top, g, static_cast<unsigned>(instanceId));
    rtcReleaseGeometry(g);
    ++instanceCount_;
  }
  rtcCommitScene(embree_.top);
  checkBuild("building the instance level");
}

void EmbreeBackend::checkBuild(const char* what) {
  errors_.throwIfFailed(what);
  RTCError e = rtcGetDeviceError(embree_.device);
  if (e != RTC_ERROR_NONE)
    throw TraceError(
        fmt::format("Embree failed while {}: error {} ({})", what, int(e), errorName(e)));
}

const Vec3f* EmbreeBackend::sharedPositions(const Mesh& mesh) {
  if (mesh.hasVertexSlack()) return mesh.positions.data();
  std::lock_guard lock(buildMutex_);  // objects are built concurrently
  auto [it, added] = paddedPositions_.try_emplace(&mesh);
  if (added) {
    std::vector<Vec3f>& copy = it->second;
    copy.reserve(mesh.positions.size() + 1);
    copy.assign(mesh.positions.begin(), mesh.positions.end());
    memory_.add(int64_t(copy.capacity() * sizeof(Vec3f)));
  }
  return it->second.data();
}

const AlphaCoverage* EmbreeBackend::coverage(const AlphaCutout& cutout) {
  const Texture& texture = *cutout.texture;
  if (texture.isSolid() || !texture.hasTexels()) return nullptr;
  auto& slot = coverages_[{&texture, cutout.cutoff, cutout.test}];
  if (!slot) {
    slot = std::make_unique<AlphaCoverage>(texture, cutout.cutoff, cutout.test);
    memory_.add(int64_t(slot->bytes()));
  }
  return slot.get();
}

template <typename IdForSlot>
void EmbreeBackend::attachMeshes(const Object& object, RTCScene target,
                                 const IdForSlot& idForSlot) {
  for (size_t slot = 0; slot < object.meshes.size(); ++slot) {
    const Mesh& mesh = scene_.meshes[object.meshes[slot]];
    FERRY_CHECK(!mesh.stored);  // stored meshes are for partitioning, never traced
    if (mesh.indices.empty()) continue;
    RTCGeometry g = rtcNewGeometry(embree_.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree only reads shared buffers; its API takes them as void*.
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               const_cast<Vec3f*>(sharedPositions(mesh)), 0, sizeof(Vec3f),
                               mesh.positions.size());
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               const_cast<Vec3i*>(mesh.indices.data()), 0, sizeof(Vec3i),
                               mesh.indices.size());
    AlphaCutout cutout = AlphaCutout::of(scene_, mesh);
    if (cutout.active()) {
      std::lock_guard lock(buildMutex_);  // objects are built concurrently
      cutout.coverage = coverage(cutout);
      auto owned = std::make_unique<EmbreeCutout>(EmbreeCutout{cutout, &scene_.instances});
      rtcSetGeometryUserData(g, owned.get());
      cutouts_.push_back(std::move(owned));
      if (cutout.test == AlphaTest::Stochastic) hashesRays_ = true;
      if (cutout.cutsPaths()) rtcSetGeometryIntersectFilterFunction(g, alphaFilter);
      if (cutout.cutsShadowRays()) rtcSetGeometryOccludedFilterFunction(g, alphaFilter);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(target, g, idForSlot(int32_t(slot)));
    rtcReleaseGeometry(g);
  }
  for (size_t k = 0; k < object.geometries.size(); ++k) {
    const Shape* shape = scene_.geometries[object.geometries[k]].shape.get();
    if (!shape || shape->primitiveCount() == 0) continue;
    if (const Shape::FlatCurves curves = shape->flatCurves(); !curves.points.empty()) {
      // Embree's own flat curves: its hit (u along the segment, v across
      // from -1 to 1) is the shape's.
      RTCGeometry g = rtcNewGeometry(embree_.device, RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE);
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                 const_cast<Vec4f*>(curves.points.data()), 0, sizeof(Vec4f),
                                 curves.points.size());
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT,
                                 const_cast<uint32_t*>(curves.first.data()), 0, sizeof(uint32_t),
                                 curves.first.size());
      rtcSetGeometryTessellationRate(g, float(curves.tessellation));
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(target, g, idForSlot(int32_t(object.meshes.size() + k)));
      rtcReleaseGeometry(g);
      continue;
    }
    RTCGeometry g = rtcNewGeometry(embree_.device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, shape->primitiveCount() * shape->piecesPerPrimitive());
    // Embree only passes the pointer back to the callbacks, which read it as const.
    rtcSetGeometryUserData(g, const_cast<Shape*>(shape));
    rtcSetGeometryBoundsFunction(g, shapeBounds, nullptr);
    rtcSetGeometryIntersectFunction(g, shapeIntersect);
    rtcSetGeometryOccludedFunction(g, shapeOccluded);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(target, g, idForSlot(int32_t(object.meshes.size() + k)));
    rtcReleaseGeometry(g);
  }
}

RTCScene EmbreeBackend::objectScene(int32_t objectId) const {
  return embree_.objectScenes.at(objectId);
}

void EmbreeBackend::buildObjectScenes(const std::vector<int32_t>& objects) {
  // Made here, one thread, so the map is only read below (and every scene is
  // released with the others if a build throws).
  for (int32_t o : objects) embree_.objectScenes[o] = rtcNewScene(embree_.device);
  // Largest first, so that the last builds to start are the short ones. An
  // object's BVH is the same whichever thread builds it and whatever else
  // builds beside it (EmbreeTraceBackend.ConcurrentBuildsAnswerAsOneThreadDoes).
  std::vector<uint64_t> triangles(objects.size(), 0);
  for (size_t k = 0; k < objects.size(); ++k) {
    for (int32_t m : scene_.objects[objects[k]].meshes)
      triangles[k] += scene_.meshes[m].triangleCount();
    for (int32_t g : scene_.objects[objects[k]].geometries)
      if (const Shape* shape = scene_.geometries[g].shape.get())
        triangles[k] += shape->primitiveCount();
  }
  std::vector<size_t> order(objects.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return triangles[a] > triangles[b]; });
  tbb::parallel_for_each(order.begin(), order.end(), [&](size_t k) {
    const RTCScene s = embree_.objectScenes.at(objects[k]);
    attachMeshes(scene_.objects[objects[k]], s, [](int32_t slot) { return unsigned(slot); });
    rtcCommitScene(s);  // Embree builds in parallel inside, on the same TBB workers
  });
  checkBuild("building an object");
}

TraceHit EmbreeBackend::hitOf(const RTCRayHit& rh) const {
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
  uint32_t geomID = rh.hit.geomID, instID = rh.hit.instID[0];
  nameHit(geomID, instID);
  return {rh.ray.tfar, int32_t(instID), int32_t(geomID), rh.hit.primID, rh.hit.u, rh.hit.v};
}

void EmbreeBackend::traceBatch(RayBatch& batch) const {
  // RayBatch::EmbreeRay must be RTCRayHit exactly (one instance level).
  static_assert(RTC_MAX_INSTANCE_LEVEL_COUNT == 1);
  static_assert(sizeof(RayBatch::EmbreeRay) == sizeof(RTCRayHit));
  static_assert(alignof(RayBatch::EmbreeRay) >= alignof(RTCRayHit));
  FERRY_SAME_OFFSET(orgX, ray.org_x)
  FERRY_SAME_OFFSET(tnear, ray.tnear)
  FERRY_SAME_OFFSET(dirX, ray.dir_x)
  FERRY_SAME_OFFSET(time, ray.time)
  FERRY_SAME_OFFSET(tfar, ray.tfar)
  FERRY_SAME_OFFSET(mask, ray.mask)
  FERRY_SAME_OFFSET(id, ray.id)
  FERRY_SAME_OFFSET(flags, ray.flags)
  FERRY_SAME_OFFSET(ngX, hit.Ng_x)
  FERRY_SAME_OFFSET(u, hit.u)
  FERRY_SAME_OFFSET(v, hit.v)
  FERRY_SAME_OFFSET(primID, hit.primID)
  FERRY_SAME_OFFSET(geomID, hit.geomID)
  FERRY_SAME_OFFSET(instID, hit.instID)
  if (hashesRays_) {
    for (size_t k = 0; k < batch.closestCount_; ++k) batch.closest_[k].hashRay();
    for (size_t k = 0; k < batch.occludedCount_; ++k) batch.occluded_[k].hashRay();
  }
  // A lone query gets a dead companion: Embree traces one ray by its
  // single-ray kernels and more by its packet kernels, whose curve crossings
  // differ in the last bits, and a hit must not depend on its neighbours.
  if (batch.closestCount_ == 1) batch.closest_[1].setDead();
  if (batch.occludedCount_ == 1) batch.occluded_[1].setDead();
  if (batch.closestCount_) {
    TraceContext context(&batch.work_);
    rtcIntersect1M(embree_.top, &context.embree, reinterpret_cast<RTCRayHit*>(batch.closest_),
                   unsigned(std::max<size_t>(batch.closestCount_, 2)), sizeof(RTCRayHit));
    if (!topLevelMeshes_.empty())
      for (size_t k = 0; k < batch.closestCount_; ++k)
        nameHit(batch.closest_[k].geomID, batch.closest_[k].instID);
  }
  if (batch.occludedCount_) {
    TraceContext context(&batch.work_);
    rtcOccluded1M(embree_.top, &context.embree, reinterpret_cast<RTCRay*>(batch.occluded_),
                  unsigned(std::max<size_t>(batch.occludedCount_, 2)), sizeof(RTCRayHit));
  }
}

void EmbreeBackend::retrace(std::span<const RetraceRay> rays, std::span<TraceHit> hits) const {
  FERRY_CHECK_EQ(rays.size(), hits.size());
  RayBatch batch;
  for (size_t begin = 0; begin < rays.size(); begin += RayBatch::kCapacity) {
    const size_t n = std::min(RayBatch::kCapacity, rays.size() - begin);
    batch.clear();
    for (size_t i = begin; i < begin + n; ++i) {
      const TraceRay q = retraceQuery(rays[i]);
      batch.addClosest(uint32_t(i), q.origin, q.direction, q.tmax, q.time);
    }
    traceBatch(batch);
    for (size_t k = 0; k < batch.closestCount(); ++k) hits[batch.closestIndex(k)] = batch.hit(k);
  }
  errors_.throwIfFailed("re-tracing");
}

TraceHit EmbreeBackend::intersect(const TraceRay& ray) const {
  TraceContext context;
  RTCRayHit rh = toEmbree(ray);
  if (hashesRays_) rh.ray.id = alphaRayHash(ray.origin, ray.direction);
  rtcIntersect1(embree_.top, &context.embree, &rh);
  errors_.throwIfFailed("tracing a ray");
  return hitOf(rh);
}

bool EmbreeBackend::occluded(const TraceRay& ray) const {
  TraceContext context;
  RTCRay r = toEmbree(ray).ray;
  if (hashesRays_) r.id = alphaRayHash(ray.origin, ray.direction);
  rtcOccluded1(embree_.top, &context.embree, &r);
  errors_.throwIfFailed("tracing a shadow ray");
  return r.tfar < 0;  // Embree marks occlusion with tfar = -inf
}

Box3f EmbreeBackend::bounds() const {
  RTCBounds b;
  rtcGetSceneBounds(embree_.top, &b);
  Box3f r;
  if (b.lower_x <= b.upper_x) {
    r.lower = {b.lower_x, b.lower_y, b.lower_z};
    r.upper = {b.upper_x, b.upper_y, b.upper_z};
  }
  return r;
}

}  // namespace

std::unique_ptr<TraceBackend> makeEmbreeBackend(const Scene& scene,
                                                std::span<const int32_t> ownedInstances,
                                                Instancing instancing) {
  return std::make_unique<EmbreeBackend>(scene, ownedInstances, instancing);
}

}  // namespace ferry
