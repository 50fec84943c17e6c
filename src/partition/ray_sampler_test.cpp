#include "partition/ray_sampler.h"
#include "partition/partitioner.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstring>

#include "io/scene_loader.h"
#include "scene/scene.h"

namespace ferry {
namespace {

bool sameRays(const RaySample& a, const RaySample& b) {
  return a.rays.size() == b.rays.size() &&
         std::memcmp(a.rays.data(), b.rays.data(), a.rays.size() * sizeof(RaySegment)) == 0;
}

TEST(RaySampler, IsAPureFunctionOfSceneAndSeedWhateverTheThreads) {
  const Scene scene = loadScene("builtin:island?scale=0.02");
  RaySamplerOptions o;
  o.paths = 2000;
  const RaySample a = sampleSceneRays(scene, o);
  RaySample single;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    single = sampleSceneRays(scene, o);
  }
  EXPECT_TRUE(sameRays(a, single));
  o.seed = 2;
  EXPECT_FALSE(sameRays(a, sampleSceneRays(scene, o)));
  EXPECT_EQ(a.paths, 2000u);
}

// Segments end at the first hit or where the ray leaves the scene's box;
// they start outside the box (outer rays) or inside it (cameras, bounces),
// and paths bounce: there are several rays per path.
TEST(RaySampler, SegmentsLieInTheScenesBox) {
  const Scene scene = loadScene("builtin:cornell");
  RaySamplerOptions o;
  o.paths = 1000;
  const RaySample sample = sampleSceneRays(scene, o);
  EXPECT_GT(sample.rays.size(), 2 * o.paths);  // outer, camera, bounces and shadow rays
  Box3f box = scene.worldBounds();
  const float slack = 1e-3f * length(box.size());
  box.lower = box.lower - Vec3f(slack, slack, slack);
  box.upper = box.upper + Vec3f(slack, slack, slack);
  size_t inside = 0;
  for (const RaySegment& r : sample.rays) {
    ASSERT_TRUE(std::isfinite(r.tmax));
    ASSERT_GE(r.tmax, 0);
    EXPECT_NEAR(length(r.direction), 1.0f, 1e-4f);
    const Vec3f end = r.origin + r.direction * r.tmax;
    EXPECT_TRUE(box.lower.x <= end.x && end.x <= box.upper.x && box.lower.y <= end.y &&
                end.y <= box.upper.y && box.lower.z <= end.z && end.z <= box.upper.z);
    inside += box.lower.x <= r.origin.x && r.origin.x <= box.upper.x && box.lower.y <= r.origin.y &&
              r.origin.y <= box.upper.y && box.lower.z <= r.origin.z && r.origin.z <= box.upper.z;
  }
  EXPECT_GT(inside, sample.rays.size() / 2);
}

TEST(RaySampler, OnlyTheRayGuidedPartitionerTracesASample) {
  for (const Partitioner* p : partitioners()) {
    Scene scene = loadScene("builtin:cornell");
    PartitionerOptions o;
    o.partitioner = p;
    o.rayPaths = 100;
    PartitionStats stats;
    partitionScene(scene, 2, o, &stats);
    EXPECT_EQ(stats.sampledRays > 0, p->tracesRays()) << p->name();
  }
}

}  // namespace
}  // namespace ferry
