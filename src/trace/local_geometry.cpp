#include "trace/local_geometry.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <unordered_map>

#include "core/error.h"
#include "scene/scene.h"

namespace ferry {
namespace {

// What the alpha filter needs to find a hit's texture coordinate.
struct AlphaContext {
  const Mesh* mesh = nullptr;
  const Texture* texture = nullptr;
  float cutoff = 0.5f;

  bool isHole(uint32_t primitive, float u, float v) const {
    const Vec3i& tri = mesh->indices[primitive];
    Vec2f uv{u, v};
    if (!mesh->uvs.empty())
      uv = mesh->uvs[tri.x] * (1 - u - v) + mesh->uvs[tri.y] * u + mesh->uvs[tri.z] * v;
    return texture->sampleAlpha(uv) < cutoff;
  }
};

// Rejects hits on transparent texels; used for both closest-hit and occlusion
// queries, so shadows see the same cut-outs as camera rays.
void alphaFilter(const RTCFilterFunctionNArguments* args) {
  const auto* ctx = static_cast<const AlphaContext*>(args->geometryUserPtr);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    float u = RTCHitN_u(args->hit, args->N, i);
    float v = RTCHitN_v(args->hit, args->N, i);
    uint32_t prim = RTCHitN_primID(args->hit, args->N, i);
    if (ctx->isHole(prim, u, v)) args->valid[i] = 0;
  }
}

bool memoryMonitor(void* user, ssize_t bytes, bool /*post*/) {
  auto* counters = static_cast<std::atomic<int64_t>*>(user);
  int64_t now = counters[0].fetch_add(bytes) + bytes;
  int64_t peak = counters[1].load();
  while (now > peak && !counters[1].compare_exchange_weak(peak, now)) {
  }
  return true;
}

void errorCallback(void* /*user*/, RTCError code, const char* message) {
  if (code == RTC_ERROR_NONE) return;
  // Embree calls this from inside its API; turn it into an exception at the
  // next check instead of throwing through C code.
  fmt::print(stderr, "embree error {}: {}\n", int(code), message ? message : "");
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
  rh.ray.mask = 0xffffffffu;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

// (Called through LocalGeometry::Impl::hitOf, which first names a hit on a
// top-level mesh as a hit through an instance.)
TraceHit fromEmbree(const RTCRayHit& rh) {
  TraceHit h;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
  h.t = rh.ray.tfar;
  h.instance = static_cast<int32_t>(rh.hit.instID[0]);
  h.meshSlot = static_cast<int32_t>(rh.hit.geomID);
  h.primitive = rh.hit.primID;
  h.u = rh.hit.u;
  h.v = rh.hit.v;
  return h;
}

// Batches small enough to stay in cache, large enough for the stream API.
constexpr size_t kStreamBatch = RayBatch::kCapacity;

}  // namespace

struct LocalGeometry::Impl {
  RTCDevice device = nullptr;
  RTCScene top = nullptr;
  std::unordered_map<int32_t, RTCScene> objectScenes;
  // Meshes attached straight to the top-level scene, by top-level geometry id
  // minus topLevelBase: the instance and mesh slot a hit on them names.
  struct TopLevelMesh {
    int32_t instance, meshSlot;
  };
  std::vector<TopLevelMesh> topLevelMeshes;
  uint32_t topLevelBase = 0;
  uint64_t topLevelObjects = 0;
  std::vector<std::unique_ptr<AlphaContext>> alphaContexts;
  std::atomic<int64_t> memory[2] = {0, 0};  // current, peak
  uint64_t instanceCount = 0;

  ~Impl() {
    if (top) rtcReleaseScene(top);
    for (auto& [id, s] : objectScenes) rtcReleaseScene(s);
    if (device) rtcReleaseDevice(device);
  }

  // A hit on a top-level mesh has no instance id and its top-level geometry
  // id: rewrite both to what a hit through an instance would have said.
  void nameHit(uint32_t& geomID, uint32_t& instID) const {
    if (geomID == RTC_INVALID_GEOMETRY_ID || instID != RTC_INVALID_GEOMETRY_ID) return;
    const TopLevelMesh& m = topLevelMeshes[geomID - topLevelBase];
    instID = uint32_t(m.instance);
    geomID = uint32_t(m.meshSlot);
  }
  TraceHit hitOf(RTCRayHit rh) const {
    nameHit(rh.hit.geomID, rh.hit.instID[0]);
    return fromEmbree(rh);
  }

  void check(const char* what) {
    RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE)
      throw std::runtime_error(fmt::format("embree failed while {} (error {}{})", what, int(e),
                                           e == RTC_ERROR_OUT_OF_MEMORY ? ": out of memory" : ""));
  }
};

LocalGeometry::LocalGeometry(Scene& scene, std::span<const int32_t> ownedInstances,
                             Instancing instancing)
    : scene_(scene), impl_(std::make_unique<Impl>()) {
  Impl& im = *impl_;
  im.device = rtcNewDevice(nullptr);
  if (!im.device) throw std::runtime_error("could not create an Embree device");
  rtcSetDeviceErrorFunction(im.device, errorCallback, nullptr);
  rtcSetDeviceMemoryMonitorFunction(im.device, memoryMonitor, im.memory);

  std::vector<int32_t> all;
  if (ownedInstances.empty()) {
    all.resize(scene.instances.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = int32_t(i);
    ownedInstances = all;
  }

  // Embree geometries for the meshes of `object`, each attached to `target`
  // by the id attach(slot) returns.
  auto attachMeshes = [&](const Object& object, RTCScene target, auto&& idForSlot) {
    for (size_t slot = 0; slot < object.meshes.size(); ++slot) {
      Mesh& mesh = scene.meshes[object.meshes[slot]];
      if (mesh.indices.empty()) continue;
      // Embree may read 16 bytes at the last vertex: give the array slack.
      mesh.positions.reserve(mesh.positions.size() + 1);
      RTCGeometry g = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                 mesh.positions.data(), 0, sizeof(Vec3f), mesh.positions.size());
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.indices.data(),
                                 0, sizeof(Vec3i), mesh.indices.size());
      const Material& material = scene.materials[mesh.material];
      if (material.alphaTexture != kNoTexture) {
        auto ctx = std::make_unique<AlphaContext>();
        ctx->mesh = &mesh;
        ctx->texture = &scene.textures[material.alphaTexture];
        ctx->cutoff = material.alphaCutoff;
        rtcSetGeometryUserData(g, ctx.get());
        rtcSetGeometryIntersectFilterFunction(g, alphaFilter);
        rtcSetGeometryOccludedFilterFunction(g, alphaFilter);
        im.alphaContexts.push_back(std::move(ctx));
      }
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(target, g, idForSlot(int32_t(slot)));
      rtcReleaseGeometry(g);
    }
  };

  auto objectScene = [&](int32_t objectId) -> RTCScene {
    auto it = im.objectScenes.find(objectId);
    if (it != im.objectScenes.end()) return it->second;
    RTCScene s = rtcNewScene(im.device);
    attachMeshes(scene.objects[objectId], s, [](int32_t slot) { return unsigned(slot); });
    rtcCommitScene(s);
    im.check("building an object");
    im.objectScenes.emplace(objectId, s);
    return s;
  };

  // Objects placed once on this rank, untransformed: their meshes go to the top level.
  std::unordered_map<int32_t, int> placements;
  for (int32_t instanceId : ownedInstances) ++placements[scene.instances[instanceId].object];
  auto atTopLevel = [&](const Instance& inst) {
    return instancing == Instancing::Shared && placements[inst.object] == 1 &&
           inst.transform.isIdentity();
  };
  im.topLevelBase = uint32_t(scene.instances.size());  // instances keep their own ids below

  im.top = rtcNewScene(im.device);
  for (int32_t instanceId : ownedInstances) {
    const Instance& inst = scene.instances[instanceId];
    if (atTopLevel(inst)) {
      attachMeshes(scene.objects[inst.object], im.top, [&](int32_t slot) {
        im.topLevelMeshes.push_back({instanceId, slot});
        return unsigned(im.topLevelBase + im.topLevelMeshes.size() - 1);
      });
      ++im.topLevelObjects;
      ++im.instanceCount;
      continue;
    }
    RTCGeometry g = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, objectScene(inst.object));
    float xfm[12];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) xfm[r * 4 + c] = inst.transform.l[r][c];
      xfm[r * 4 + 3] = inst.transform.t[r];
    }
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, xfm);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(im.top, g, static_cast<unsigned>(instanceId));
    rtcReleaseGeometry(g);
    ++im.instanceCount;
  }
  rtcCommitScene(im.top);
  im.check("building the instance level");
}

LocalGeometry::~LocalGeometry() = default;

TraceHit LocalGeometry::intersect(const TraceRay& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh = toEmbree(ray);
  rtcIntersect1(impl_->top, &context, &rh);
  return impl_->hitOf(rh);
}

bool LocalGeometry::occluded(const TraceRay& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay r = toEmbree(ray).ray;
  rtcOccluded1(impl_->top, &context, &r);
  return r.tfar < 0;  // Embree marks occlusion with tfar = -inf
}

void LocalGeometry::intersect(std::span<const TraceRay> rays, std::span<TraceHit> hits) const {
  FERRY_CHECK(rays.size() == hits.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kStreamBatch),
                    [&](const tbb::blocked_range<size_t>& range) {
                      RTCRayHit batch[kStreamBatch];
                      for (size_t begin = range.begin(); begin < range.end();
                           begin += kStreamBatch) {
                        size_t n = std::min(kStreamBatch, range.end() - begin);
                        for (size_t i = 0; i < n; ++i) batch[i] = toEmbree(rays[begin + i]);
                        RTCIntersectContext context;
                        rtcInitIntersectContext(&context);
                        rtcIntersect1M(impl_->top, &context, batch, unsigned(n), sizeof(RTCRayHit));
                        for (size_t i = 0; i < n; ++i) hits[begin + i] = impl_->hitOf(batch[i]);
                      }
                    });
}

void LocalGeometry::occluded(std::span<const TraceRay> rays, std::span<uint8_t> occluded) const {
  FERRY_CHECK(rays.size() == occluded.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kStreamBatch),
                    [&](const tbb::blocked_range<size_t>& range) {
                      RTCRay batch[kStreamBatch];
                      for (size_t begin = range.begin(); begin < range.end();
                           begin += kStreamBatch) {
                        size_t n = std::min(kStreamBatch, range.end() - begin);
                        for (size_t i = 0; i < n; ++i) batch[i] = toEmbree(rays[begin + i]).ray;
                        RTCIntersectContext context;
                        rtcInitIntersectContext(&context);
                        rtcOccluded1M(impl_->top, &context, batch, unsigned(n), sizeof(RTCRay));
                        for (size_t i = 0; i < n; ++i) occluded[begin + i] = batch[i].tfar < 0;
                      }
                    });
}

void LocalGeometry::trace(RayBatch& batch) const {
  // RayBatch::EmbreeRay must be RTCRayHit exactly (one instance level).
#define FERRY_SAME_OFFSET(ours, theirs) \
  static_assert(offsetof(RayBatch::EmbreeRay, ours) == offsetof(RTCRayHit, theirs), #ours);
  static_assert(RTC_MAX_INSTANCE_LEVEL_COUNT == 1);
  static_assert(sizeof(RayBatch::EmbreeRay) == sizeof(RTCRayHit));
  static_assert(alignof(RayBatch::EmbreeRay) >= alignof(RTCRayHit));
  static_assert(RayBatch::kNoGeometry == RTC_INVALID_GEOMETRY_ID);
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
#undef FERRY_SAME_OFFSET
  RTCIntersectContext context;
  if (batch.closestCount_) {
    rtcInitIntersectContext(&context);
    rtcIntersect1M(impl_->top, &context, reinterpret_cast<RTCRayHit*>(batch.closest_),
                   unsigned(batch.closestCount_), sizeof(RTCRayHit));
    if (!impl_->topLevelMeshes.empty())
      for (size_t k = 0; k < batch.closestCount_; ++k)
        impl_->nameHit(batch.closest_[k].geomID, batch.closest_[k].instID);
  }
  if (batch.occludedCount_) {
    rtcInitIntersectContext(&context);
    rtcOccluded1M(impl_->top, &context, reinterpret_cast<RTCRay*>(batch.occluded_),
                  unsigned(batch.occludedCount_), sizeof(RTCRayHit));
  }
}

void LocalGeometry::traceBatch(std::span<const TraceRay> rays, std::span<const TraceQuery> queries,
                               std::span<TraceHit> hits, std::span<uint8_t> occluded) const {
  FERRY_CHECK(rays.size() == queries.size() && rays.size() == hits.size() &&
              rays.size() == occluded.size());
  RayBatch batch;
  for (size_t begin = 0; begin < rays.size(); begin += RayBatch::kCapacity) {
    const size_t n = std::min(RayBatch::kCapacity, rays.size() - begin);
    batch.clear();
    for (size_t i = begin; i < begin + n; ++i) {
      const TraceRay& r = rays[i];
      if (queries[i] == TraceQuery::Closest)
        batch.addClosest(uint32_t(i), r.origin, r.direction, r.tmax, r.tnear);
      else if (queries[i] == TraceQuery::Occluded)
        batch.addOccluded(uint32_t(i), r.origin, r.direction, r.tmax, r.tnear);
    }
    trace(batch);
    for (size_t k = 0; k < batch.closestCount(); ++k) hits[batch.closestIndex(k)] = batch.hit(k);
    for (size_t k = 0; k < batch.occludedCount(); ++k)
      occluded[batch.occludedIndex(k)] = batch.isOccluded(k);
  }
}

Box3f LocalGeometry::bounds() const {
  RTCBounds b;
  rtcGetSceneBounds(impl_->top, &b);
  Box3f r;
  if (b.lower_x <= b.upper_x) {
    r.lower = {b.lower_x, b.lower_y, b.lower_z};
    r.upper = {b.upper_x, b.upper_y, b.upper_z};
  }
  return r;
}

int64_t LocalGeometry::embreeBytes() const {
  return impl_->memory[0].load();
}
int64_t LocalGeometry::embreePeakBytes() const {
  return impl_->memory[1].load();
}
uint64_t LocalGeometry::builtObjectCount() const {
  return impl_->objectScenes.size() + impl_->topLevelObjects;
}
uint64_t LocalGeometry::topLevelObjectCount() const {
  return impl_->topLevelObjects;
}
uint64_t LocalGeometry::builtInstanceCount() const {
  return impl_->instanceCount;
}

}  // namespace ferry
