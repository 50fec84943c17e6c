// The landscape after pbrt's landscape scene: its published structure (29
// objects, 370 meshes) and ratios (instances and instanced triangles per
// unique triangle, triangles per instance), docs/scenes.md, L1.
#include "builtin/landscape.h"

#include <chrono>
#include <cstdio>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "builtin/builtin.h"
#include "scene/memory_cost.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

const Scene& landscape() {
  static const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:landscape"));
  return scene;
}

// L1: miniInfo on pbrt-v3's landscape (view-0), quoted in the miniScene README.
constexpr double kPublishedObjects = 29;
constexpr double kPublishedMeshes = 370;
constexpr double kPublishedInstances = 30035;
constexpr double kPublishedUniqueTriangles = 27.78e6;
constexpr double kPublishedInstancedTriangles = 4.35e9;

struct ObjectStats {
  uint64_t meshes = 0, triangles = 0, instances = 0, bytes = 0;
};

// Per object, from the plan's counts alone (as `ferry info` sees them); the
// table in docs/scenes.md is this test's output.
std::map<std::string, ObjectStats> describedObjects(const builtin::ScenePlan& plan) {
  std::map<std::string, ObjectStats> stats;
  std::vector<uint64_t> instances(plan.objects.size(), 0);
  for (const builtin::InstanceBatch& b : plan.batches) instances[size_t(b.object)] += b.count;
  for (size_t o = 0; o < plan.objects.size(); ++o) {
    ObjectStats& s = stats[plan.objects[o].name];
    for (int32_t m : plan.objects[o].meshes) {
      const builtin::MeshRecipe& r = plan.meshes[size_t(m)];
      s.bytes += meshCost(r.counts.vertices, r.counts.triangles, r.hasNormals, r.hasUvs).total();
      s.triangles += r.counts.triangles;
      ++s.meshes;
    }
    s.instances = instances[o];
    s.bytes += instanceCost(instances[o]).total();
  }
  return stats;
}

TEST(Landscape, HasThePublishedNumberOfObjectsAndMeshes) {
  SceneSummary s = describeBuiltin(parseBuiltinSpec("builtin:landscape"));
  EXPECT_EQ(double(s.objects), kPublishedObjects);
  EXPECT_EQ(double(s.uniqueMeshes), kPublishedMeshes);
  // Every object is instanced; the ground is one object of tiles, placed once.
  std::map<std::string, ObjectStats> objects = describedObjects(builtin::planLandscape(1, 1));
  for (const auto& [name, o] : objects) EXPECT_GE(o.instances, 1u) << name;
  EXPECT_EQ(objects.at("ground").instances, 1u);
  EXPECT_EQ(objects.at("ground").meshes, 225u);
}

TEST(Landscape, KeepsThePublishedRatios) {
  SceneSummary s = describeBuiltin(parseBuiltinSpec("builtin:landscape"));
  const double unique = double(s.triangles);
  auto near = [](double ours, double published) {
    EXPECT_GT(ours, 0.75 * published);
    EXPECT_LT(ours, 1.25 * published);
  };
  near(double(s.instances) / unique, kPublishedInstances / kPublishedUniqueTriangles);
  near(double(s.instancedTriangles) / unique,
       kPublishedInstancedTriangles / kPublishedUniqueTriangles);
  near(double(s.instancedTriangles) / double(s.instances),
       kPublishedInstancedTriangles / kPublishedInstances);
  EXPECT_EQ(s.suns, 1u);
  EXPECT_EQ(s.environments, 1u);
}

TEST(Landscape, PrintsItsObjects) {
  std::map<std::string, ObjectStats> objects = describedObjects(builtin::planLandscape(1, 1));
  uint64_t bytes = 0;
  for (const auto& [name, o] : objects) bytes += o.bytes;
  std::printf("| object | meshes | triangles | instances | instanced triangles | %% of bytes |\n");
  for (const auto& [name, o] : objects)
    std::printf("| %s | %llu | %llu | %llu | %.1f M | %.1f%% |\n", name.c_str(),
                (unsigned long long)o.meshes, (unsigned long long)o.triangles,
                (unsigned long long)o.instances, double(o.triangles * o.instances) / 1e6,
                100.0 * double(o.bytes) / double(bytes));
  EXPECT_EQ(objects.size(), size_t(kPublishedObjects));
}

TEST(Landscape, HasSeveralAlphaTextures) {
  const Scene& scene = landscape();
  std::set<int32_t> alpha;
  for (const Material& m : scene.materials)
    if (m.alphaTexture != kNoTexture) alpha.insert(m.alphaTexture);
  EXPECT_GE(alpha.size(), 5u);
  for (int32_t t : alpha) {
    const Texture& tex = scene.textures[t];
    size_t holes = 0;
    for (size_t i = 3; i < tex.rgba.size(); i += 4) holes += tex.rgba[i] < 128;
    EXPECT_GT(holes, 0u) << tex.name;
    EXPECT_LT(holes, tex.texelCount()) << tex.name;
  }
  EXPECT_GE(scene.textures.size(), 10u);
}

TEST(Landscape, PathViewStandsOnTheGround) {
  const Scene& scene = landscape();
  const CameraView& path = scene.view("path");
  // The eye is a person's height above the ground tile under it.
  float nearest = 1e30f, groundY = 0;
  for (const Mesh& m : scene.meshes) {
    if (m.name.rfind("ground/", 0) != 0) continue;
    for (const Vec3f& p : m.positions) {
      float d =
          (p.x - path.from.x) * (p.x - path.from.x) + (p.z - path.from.z) * (p.z - path.from.z);
      if (d < nearest) nearest = d, groundY = p.y;
    }
  }
  ASSERT_LT(nearest, 4.0f);
  EXPECT_NEAR(path.from.y - groundY, 1.7f, 0.5f);
}

// `ferry info` answers from the plan's counts: at scale 100 (46.8 G
// instanced triangles) and far beyond, nothing is made.
TEST(Landscape, LargeScalesAreDescribedFromCounts) {
  const auto start = std::chrono::steady_clock::now();
  SceneSummary large = describeBuiltin(parseBuiltinSpec("builtin:landscape?scale=100"));
  SceneSummary huge = describeBuiltin(parseBuiltinSpec("builtin:landscape?scale=1000000"));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(large.instancedTriangles, 40'000'000'000ull);
  EXPECT_GT(large.triangles, 200'000'000ull);
  EXPECT_EQ(double(large.objects), kPublishedObjects);
  EXPECT_GT(huge.instancedTriangles, large.instancedTriangles);
  EXPECT_LT(seconds, 2.0);
}

TEST(Landscape, ScaleGrowsInstancesNotObjects) {
  SceneSummary one = describeBuiltin(parseBuiltinSpec("builtin:landscape"));
  SceneSummary three = describeBuiltin(parseBuiltinSpec("builtin:landscape?scale=3"));
  EXPECT_EQ(one.objects, three.objects);
  EXPECT_EQ(one.uniqueMeshes, three.uniqueMeshes);
  EXPECT_NEAR(double(three.instances) / double(one.instances), 3.0, 0.1);
  EXPECT_GT(three.triangles, one.triangles);  // a finer ground
}

}  // namespace
}  // namespace ferry
