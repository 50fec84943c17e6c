// Keeping the hit (--retrace remote) must change nothing but the speed: the
// hit a rank's trace found and the one shading's re-trace query finds are the
// same hit, bit for bit, so the surface rebuilt from either is the same.
// Checked ray by ray here (camera rays and random secondary rays from the hit
// points, on the built-in Cornell box and island), and image by image in
// determinism_test.cpp. Also: the precomputed instance inverses give the
// same surface as inverting per hit.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <span>

#include "builtin/builtin.h"
#include "core/random.h"
#include "material/bsdf.h"
#include "path/path.h"
#include "render/camera.h"
#include "render/surface.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"
#include "trace/reference_backend.h"

namespace ferry {
namespace {

bool same(const void* a, const void* b, size_t n) {
  return std::memcmp(a, b, n) == 0;
}

bool sameHit(const TraceHit& a, const TraceHit& b) {
  return a.instance == b.instance && a.slot == b.slot && a.primitive == b.primitive &&
         same(&a.u, &b.u, 4) && same(&a.v, &b.v, 4);
}

bool sameSurface(const SurfacePoint& a, const SurfacePoint& b) {
  return same(&a.position, &b.position, sizeof(Vec3f)) &&
         same(&a.geometricNormal, &b.geometricNormal, sizeof(Vec3f)) &&
         same(&a.shadingNormal, &b.shadingNormal, sizeof(Vec3f)) &&
         same(&a.uv, &b.uv, sizeof(Vec2f)) && a.material == b.material &&
         same(&a.baseColor, &b.baseColor, sizeof(Vec3f));
}

// Traces camera rays, then two generations of cosine-distributed rays from
// the hits, through the backend's wavefront trace (which keeps the hits);
// re-traces every hit path as shade does, in one batch and one by one;
// counts paths checked.
using BackendFactory = std::unique_ptr<TraceBackend> (*)(const Scene&, std::span<const int32_t>,
                                                         Instancing);

size_t checkScene(const std::string& spec, int width, int height,
                  BackendFactory makeBackend = makeEmbreeBackend) {
  Scene scene = generateBuiltin(parseBuiltinSpec(spec));
  const std::unique_ptr<TraceBackend> geometry = makeBackend(scene, {}, Instancing::Shared);
  const std::vector<Affine3f> inverses = instanceInverses(scene);
  Camera camera(scene.view(""), width, height);
  PathQueue<Path8> rays;
  for (uint32_t pixel = 0; pixel < uint32_t(width * height); ++pixel) {
    Path8 p{};
    p.origin = camera.origin();
    p.setDir(camera.direction(float(pixel % width) + 0.5f, float(pixel / width) + 0.5f));
    p.tmax = kInfinity;
    p.setWeight(Vec3f(1));
    p.setPixelAndFlags(pixel, 0);
    rays.push_back(p);
  }
  size_t checked = 0;
  for (uint32_t generation = 0; generation < 3 && !rays.empty(); ++generation) {
    std::vector<TraceHit> kept(rays.size());
    geometry->trace(rays, 1, {}, kept);
    std::vector<RetraceRay> queries;
    for (const Path8& p : rays) queries.push_back({p.origin, p.dir(), p.tmax});
    std::vector<TraceHit> batched(rays.size());
    geometry->retrace(queries, batched);
    PathQueue<Path8> next;
    for (size_t i = 0; i < rays.size(); ++i) {
      const Path8& p = rays[i];
      EXPECT_EQ(kept[i].valid(), p.hasHit()) << spec << " ray " << i;
      if (!p.hasHit()) continue;
      TraceHit single;
      geometry->retrace(std::span(&queries[i], 1), std::span(&single, 1));
      if (!kept[i].valid()) continue;  // reported above
      EXPECT_TRUE(sameHit(kept[i], single)) << spec << " generation " << generation << " ray " << i;
      EXPECT_TRUE(sameHit(kept[i], batched[i]))
          << spec << " generation " << generation << " ray " << i;
      EXPECT_EQ(kept[i].t, p.tmax);
      SurfacePoint fromKept = reconstructSurface(scene, kept[i]);
      SurfacePoint fromRetrace = reconstructSurface(scene, batched[i]);
      EXPECT_TRUE(sameSurface(fromKept, fromRetrace)) << spec << " ray " << i;
      // With the per-instance inverses precomputed (as the renderer does): the same surface.
      EXPECT_TRUE(sameSurface(fromKept, reconstructSurface(scene, kept[i], &inverses)))
          << spec << " ray " << i;
      ++checked;
      // A secondary ray from the hit, as shading would spawn it.
      Vec3f ng = fromKept.geometricNormal;
      if (dot(ng, p.dir()) > 0) ng = -ng;
      RandomKey key{p.pixel(), 0, generation, 7};
      Vec3f wi = Frame(ng).toWorld(sampleCosineHemisphere(
          {random01(key, RandomDim::BsdfU), random01(key, RandomDim::BsdfV)}));
      Path8 q = p;
      q.origin = offsetRayOrigin(fromKept.position, ng);
      q.setDir(wi);
      q.tmax = kInfinity;
      q.hitOwners = 0;
      q.visited = 0;
      next.push_back(q);
    }
    rays = std::move(next);
  }
  return checked;
}

TEST(Retrace, KeptHitEqualsRetracedHitOnTheCornellBox) {
  EXPECT_GT(checkScene("builtin:cornell", 64, 64), 64u * 64u);
}

TEST(Retrace, KeptHitEqualsRetracedHitOnTheIsland) {
  // Instances, alpha-tested leaves (filter functions) and large coordinates.
  EXPECT_GT(checkScene("builtin:island?scale=0.05", 64, 36), 1000u);
}

// The re-trace tolerance belongs to the backend: the reference backend's own
// (the next float past the recorded distance) finds its hits again too.
TEST(Retrace, KeptHitEqualsRetracedHitWithTheReferenceBackend) {
  EXPECT_GT(checkScene("builtin:cornell", 32, 32, makeReferenceBackend), 32u * 32u);
  EXPECT_GT(checkScene("builtin:island?scale=0.02", 48, 27, makeReferenceBackend), 500u);
}

}  // namespace
}  // namespace ferry
