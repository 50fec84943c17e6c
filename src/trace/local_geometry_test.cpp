// The instance level is a speed decision, not a change of what is hit: with
// Instancing::Shared (objects placed once, untransformed, at the top level)
// and Instancing::Always (every object instanced) every query answers alike,
// naming the same instance, mesh slot and triangle.
#include "trace/local_geometry.h"

#include <gtest/gtest.h>

#include <cstring>

#include "builtin/builtin.h"
#include "core/random.h"
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

void expectSameAnswers(const std::string& spec, bool someStayInstanced) {
  Scene scene = generateBuiltin(parseBuiltinSpec(spec));
  LocalGeometry shared(scene, {}, Instancing::Shared);
  LocalGeometry always(scene, {}, Instancing::Always);
  EXPECT_GT(shared.topLevelObjectCount(), 0u) << spec;
  EXPECT_EQ(always.topLevelObjectCount(), 0u) << spec;
  EXPECT_EQ(shared.builtInstanceCount(), always.builtInstanceCount());
  EXPECT_EQ(shared.builtObjectCount(), always.builtObjectCount());
  if (someStayInstanced) {
    EXPECT_LT(shared.topLevelObjectCount(), shared.builtObjectCount()) << spec;
  }

  const std::vector<TraceRay> rays = randomRays(always.bounds(), 20000);
  std::vector<TraceHit> a(rays.size()), b(rays.size());
  shared.intersect(rays, a);
  always.intersect(rays, b);
  std::vector<uint8_t> occludedA(rays.size()), occludedB(rays.size());
  shared.occluded(rays, occludedA);
  always.occluded(rays, occludedB);
  size_t hits = 0, tiedElsewhere = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(a[i].valid(), b[i].valid()) << i;
    ASSERT_EQ(occludedA[i], occludedB[i]) << i;
    if (!a[i].valid()) continue;
    ++hits;
    ASSERT_EQ(std::memcmp(&a[i].t, &b[i].t, 4), 0) << i;
    // The same distance on another triangle (a shared edge) may be found
    // first in the other BVH; anything else must name the same triangle.
    if (a[i].instance != b[i].instance || a[i].meshSlot != b[i].meshSlot ||
        a[i].primitive != b[i].primitive) {
      ++tiedElsewhere;
      continue;
    }
    EXPECT_EQ(std::memcmp(&a[i].u, &b[i].u, 4), 0) << i;
    EXPECT_EQ(std::memcmp(&a[i].v, &b[i].v, 4), 0) << i;
    // The single-ray query names hits the same way.
    TraceHit single = shared.intersect(rays[i]);
    EXPECT_EQ(single.instance, a[i].instance);
    EXPECT_EQ(single.meshSlot, a[i].meshSlot);
  }
  EXPECT_GT(hits, rays.size() / 4) << spec;
  EXPECT_LE(tiedElsewhere, hits / 1000) << spec;

  // The batch the renderer uses (RayBatch, mixed queries) agrees too.
  RayBatch batch;
  for (uint32_t i = 0; i < RayBatch::kCapacity; ++i) {
    if (i % 2)
      batch.addClosest(i, rays[i].origin, rays[i].direction, rays[i].tmax);
    else
      batch.addOccluded(i, rays[i].origin, rays[i].direction, rays[i].tmax);
  }
  shared.trace(batch);
  for (size_t k = 0; k < batch.closestCount(); ++k) {
    const uint32_t i = batch.closestIndex(k);
    const TraceHit h = batch.hit(k);
    EXPECT_EQ(h.valid(), b[i].valid());
    if (h.valid() && b[i].valid() && h.primitive == b[i].primitive) {
      EXPECT_EQ(h.instance, b[i].instance);
      EXPECT_EQ(h.meshSlot, b[i].meshSlot);
    }
  }
  for (size_t k = 0; k < batch.occludedCount(); ++k)
    EXPECT_EQ(batch.isOccluded(k), occludedB[batch.occludedIndex(k)] != 0);
}

TEST(LocalGeometry, SharedAndAlwaysInstancingAnswerAlikeOnTheCornellBox) {
  expectSameAnswers("builtin:cornell", false);
}

TEST(LocalGeometry, SharedAndAlwaysInstancingAnswerAlikeOnTheIsland) {
  // Terrain and water are placed once; the plants are instanced many times.
  expectSameAnswers("builtin:island?scale=0.05", true);
}

}  // namespace
}  // namespace ferry
