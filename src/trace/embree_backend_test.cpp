// The instance level is a speed decision, not a change of what is hit: with
// Instancing::Shared (objects placed once, untransformed, at the top level)
// and Instancing::Always (every object instanced) every query answers alike,
// naming the same instance, mesh slot and triangle.
#include "trace/embree_backend.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <cstring>
#include <memory>

#include "builtin/builtin.h"
#include "core/floating_point_mode.h"
#include "core/random.h"
#include "path/path.h"
#include "scene/scene.h"

namespace ferry {
namespace {

float uniform(uint32_t i, uint32_t d) {
  return random01(RandomKey{i, 0, 0, 17}, RandomDim(d % 8));
}

// Rays from random points of the scene's bounds in random directions.
std::vector<TraceRay> randomRays(const Box3f& b, size_t n) {
  std::vector<TraceRay> rays(n);
  for (uint32_t i = 0; i < n; ++i) {
    Vec3f o{b.lower.x + (b.upper.x - b.lower.x) * uniform(i, 0),
            b.lower.y + (b.upper.y - b.lower.y) * uniform(i, 1),
            b.lower.z + (b.upper.z - b.lower.z) * uniform(i, 2)};
    Vec3f d = normalize(Vec3f(uniform(i, 3), uniform(i, 4), uniform(i, 5)) - Vec3f(0.5f));
    rays[i] = TraceRay{o, d, 0, i % 3 == 0 ? kInfinity : 0.3f * length(b.upper - b.lower)};
  }
  return rays;
}

// Rays as paths (closest-hit queries), or shadow rays when `shadow`.
PathQueue<Path8> asPaths(const std::vector<TraceRay>& rays, bool shadow) {
  PathQueue<Path8> paths(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    Path8& p = paths[i];
    p.origin = rays[i].origin;
    p.setDirAndWeight(rays[i].direction, Vec3f(1));
    p.tmax = rays[i].tmax;
    p.setPixelAndFlags(uint32_t(i), shadow ? uint32_t(kPathShadow) : 0u);
    p.clearHistory();
  }
  return paths;
}

void expectSameAnswers(const std::string& spec, bool someStayInstanced) {
  Scene scene = generateBuiltin(parseBuiltinSpec(spec));
  const std::unique_ptr<TraceBackend> shared = makeEmbreeBackend(scene, {}, Instancing::Shared);
  const std::unique_ptr<TraceBackend> always = makeEmbreeBackend(scene, {}, Instancing::Always);
  const BuiltCounts builtShared = shared->built(), builtAlways = always->built();
  EXPECT_GT(builtShared.topLevelObjects, 0u) << spec;
  EXPECT_EQ(builtAlways.topLevelObjects, 0u) << spec;
  EXPECT_EQ(builtShared.instances, builtAlways.instances);
  EXPECT_EQ(builtShared.objects, builtAlways.objects);
  if (someStayInstanced) {
    EXPECT_LT(builtShared.topLevelObjects, builtShared.objects) << spec;
  }

  // The wavefront trace, as the renderer calls it: closest hits kept, shadow rays marked.
  const std::vector<TraceRay> rays = randomRays(always->bounds(), 20000);
  PathQueue<Path8> pathsA = asPaths(rays, false), pathsB = pathsA;
  PathQueue<Path8> shadowsA = asPaths(rays, true), shadowsB = shadowsA;
  std::vector<TraceHit> a(rays.size()), b(rays.size());
  const TraceCounts countsA = shared->trace(pathsA, 0, {}, a);
  always->trace(pathsB, 0, {}, b);
  const TraceCounts shadowCounts = shared->trace(shadowsA, 0, {});
  always->trace(shadowsB, 0, {});
  EXPECT_EQ(countsA.closest, rays.size());
  EXPECT_EQ(countsA.occlusion, 0u);
  EXPECT_EQ(shadowCounts.closest, 0u);
  EXPECT_EQ(shadowCounts.occlusion, rays.size());
  size_t hits = 0, tiedElsewhere = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(a[i].valid(), b[i].valid()) << i;
    const bool occludedA = shadowsA[i].has(kPathOccluded),
               occludedB = shadowsB[i].has(kPathOccluded);
    ASSERT_EQ(occludedA, occludedB) << i;
    // The single-ray queries answer as the wavefront trace does.
    const TraceRay asTraced{pathsA[i].origin, shadowsA[i].dir(), 0, rays[i].tmax};
    EXPECT_EQ(shared->occluded(asTraced), occludedA) << i;
    if (!a[i].valid()) continue;
    ++hits;
    ASSERT_EQ(std::memcmp(&a[i].t, &b[i].t, 4), 0) << i;
    EXPECT_EQ(pathsA[i].tmax, a[i].t);
    EXPECT_TRUE(pathsA[i].hasHit());
    // The same distance on another triangle (a shared edge) may be found
    // first in the other BVH; anything else must name the same triangle.
    if (a[i].instance != b[i].instance || a[i].slot != b[i].slot ||
        a[i].primitive != b[i].primitive) {
      ++tiedElsewhere;
      continue;
    }
    EXPECT_EQ(std::memcmp(&a[i].u, &b[i].u, 4), 0) << i;
    EXPECT_EQ(std::memcmp(&a[i].v, &b[i].v, 4), 0) << i;
    // The single-ray query names hits the same way.
    TraceHit single = shared->intersect(asTraced);
    EXPECT_EQ(single.instance, a[i].instance);
    EXPECT_EQ(single.slot, a[i].slot);
  }
  EXPECT_GT(hits, rays.size() / 4) << spec;
  EXPECT_LE(tiedElsewhere, hits / 1000) << spec;
}

TEST(EmbreeTraceBackend, SharedAndAlwaysInstancingAnswerAlikeOnTheCornellBox) {
  expectSameAnswers("builtin:cornell", false);
}

TEST(EmbreeTraceBackend, SharedAndAlwaysInstancingAnswerAlikeOnTheIsland) {
  // Terrain and water are placed once; the plants are instanced many times.
  expectSameAnswers("builtin:island?scale=0.05", true);
}

// Instanced objects' BVHs are built concurrently, and Embree builds each in
// parallel too: the trees, and so every hit (distance, triangle, barycentrics
// bit for bit), must not depend on how many threads built them.
TEST(EmbreeTraceBackend, ConcurrentBuildsAnswerAsOneThreadDoes) {
  const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.05"));
  std::unique_ptr<TraceBackend> oneThread;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    oneThread = makeEmbreeBackend(scene, {}, Instancing::Always);
  }
  const std::unique_ptr<TraceBackend> concurrent = makeEmbreeBackend(scene, {}, Instancing::Always);
  EXPECT_GT(concurrent->built().objects, 50u);
  const std::vector<TraceRay> rays = randomRays(scene.worldBounds(), 20000);
  size_t hits = 0;
  for (const TraceRay& r : rays) {
    const TraceHit a = oneThread->intersect(r), b = concurrent->intersect(r);
    ASSERT_EQ(std::memcmp(&a, &b, sizeof(TraceHit)), 0);
    hits += a.instance >= 0;
  }
  EXPECT_GT(hits, rays.size() / 4);
}

// Embree switches the floating-point mode inside its builds; the mode the
// renderer's threads run in is the one main() set, before and after.
TEST(EmbreeTraceBackend, BuildsLeaveTheFloatingPointModeAsMainSetIt) {
  const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.05"));
  const std::unique_ptr<TraceBackend> backend = makeEmbreeBackend(scene);
  EXPECT_TRUE(floatingPointModeIsFixed());
  std::atomic<int> outside{0};
  tbb::parallel_for(0, 10000, [&](int) {
    if (!floatingPointModeIsFixed()) ++outside;
  });
  EXPECT_EQ(outside.load(), 0);
}

}  // namespace
}  // namespace ferry

namespace ferry {
namespace {

// A ray's answer must not depend on the rays traced beside it: a wavefront
// of one ray answers as a wavefront of many, bit for bit (the overlapped
// exchange traces whatever has arrived, sometimes one ray, and Embree's
// single-ray and packet kernels cross curves differently in the last bits).
// The single-ray queries (Embree's single-ray kernels, for one-off queries
// and medium boundaries) answer alike on triangles.
void expectAloneAsInABatch(const std::string& spec, bool trianglesOnly) {
  const Scene scene = generateBuiltin(parseBuiltinSpec(spec));
  const std::unique_ptr<TraceBackend> backend = makeEmbreeBackend(scene);
  const std::vector<TraceRay> rays = randomRays(backend->bounds(), 4000);
  PathQueue<Path8> paths = asPaths(rays, false), shadows = asPaths(rays, true);
  std::vector<TraceHit> many(rays.size());
  backend->trace(paths, 0, {}, many);
  backend->trace(shadows, 0, {});
  size_t hits = 0, differ = 0, singleDiffers = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    PathQueue<Path8> one = asPaths({rays[i]}, false), oneShadow = asPaths({rays[i]}, true);
    std::vector<TraceHit> alone(1);
    backend->trace(one, 0, {}, alone);
    backend->trace(oneShadow, 0, {});
    hits += many[i].valid();
    const bool occluded = shadows[i].has(kPathOccluded);
    differ += std::memcmp(&many[i], &alone[0], sizeof(TraceHit)) != 0;
    differ += oneShadow[0].has(kPathOccluded) != occluded;
    // As the paths store it (their direction is packed).
    const TraceRay asTraced{paths[i].origin, paths[i].dir(), 0, rays[i].tmax};
    const TraceHit single = backend->intersect(asTraced);
    singleDiffers += std::memcmp(&many[i], &single, sizeof(TraceHit)) != 0;
    singleDiffers += backend->occluded(asTraced) != occluded;
  }
  EXPECT_GT(hits, rays.size() / 20) << spec;
  EXPECT_EQ(differ, 0u) << spec;
  if (trianglesOnly) {
    EXPECT_EQ(singleDiffers, 0u) << spec;
  }
}

TEST(EmbreeTraceBackend, ARayAloneIsTracedAsInABatch) {
  expectAloneAsInABatch("builtin:cornell", true);
  expectAloneAsInABatch("builtin:fur?strands=2000", false);
}

}  // namespace
}  // namespace ferry
