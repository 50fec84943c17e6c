// The island's shape as a benchmark scene: many instanced species of
// production-like size, a hero object, lights, and a scale knob that reaches
// 1e10 instanced triangles in its description.
#include "builtin/island.h"

#include <chrono>
#include <map>

#include <gtest/gtest.h>

#include "builtin/builtin.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

const Scene& island() {
  static const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island"));
  return scene;
}

struct SpeciesStats {
  uint64_t instances = 0;
  uint64_t minTriangles = UINT64_MAX, maxTriangles = 0;
  int objects = 0;
};

// Objects are named "<species>/<variant>"; single set pieces have no '/'.
std::map<std::string, SpeciesStats> speciesStats(const Scene& scene) {
  std::vector<uint32_t> counts = scene.instanceCountPerObject();
  std::map<std::string, SpeciesStats> stats;
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    const std::string& name = scene.objects[o].name;
    size_t slash = name.find('/');
    if (slash == std::string::npos) continue;
    uint64_t triangles = 0;
    for (int32_t m : scene.objects[o].meshes) triangles += scene.meshes[m].triangleCount();
    SpeciesStats& s = stats[name.substr(0, slash)];
    s.instances += counts[o];
    s.minTriangles = std::min(s.minTriangles, triangles);
    s.maxTriangles = std::max(s.maxTriangles, triangles);
    ++s.objects;
  }
  return stats;
}

TEST(Island, HasAtLeastEightMultiInstanceSpeciesOfProductionSize) {
  std::map<std::string, SpeciesStats> stats = speciesStats(island());
  EXPECT_GE(stats.size(), 8u);
  uint64_t fewest = UINT64_MAX, most = 0;
  for (const auto& [name, s] : stats) {
    SCOPED_TRACE(name);
    EXPECT_GE(s.minTriangles, 1000u);
    EXPECT_LE(s.maxTriangles, 500000u);
    EXPECT_GT(s.instances, uint64_t(s.objects));  // instanced more than once per variant
    fewest = std::min(fewest, s.instances);
    most = std::max(most, s.instances);
  }
  // From tens to tens of thousands of instances per species.
  EXPECT_GE(fewest, 10u);
  EXPECT_LT(fewest, 100u);
  EXPECT_GE(most, 10000u);
  EXPECT_LT(most, 100000u);
}

TEST(Island, EverySpeciesObjectIsSeveralMeshesOrARock) {
  const Scene& scene = island();
  int multiMesh = 0;
  for (const Object& o : scene.objects)
    if (o.name.find('/') != std::string::npos && o.meshes.size() >= 2) ++multiMesh;
  EXPECT_GT(multiMesh, 8);
}

TEST(Island, LeavesAreAlphaCutCardsSharingOneTexture) {
  const Scene& scene = island();
  int32_t leafTexture = kNoTexture;
  for (const Material& m : scene.materials)
    if (m.name == "leaves") leafTexture = m.alphaTexture;
  ASSERT_NE(leafTexture, kNoTexture);
  const Texture& t = scene.textures[leafTexture];
  size_t holes = 0, solid = 0;
  for (size_t i = 3; i < t.rgba.size(); i += 4) (t.rgba[i] < 128 ? holes : solid)++;
  EXPECT_GT(holes, t.texelCount() / 10);
  EXPECT_GT(solid, t.texelCount() / 10);
  // Trees, bushes and flowers all use it.
  int users = 0;
  for (const Mesh& m : scene.meshes)
    if (scene.materials[m.material].alphaTexture == leafTexture) ++users;
  EXPECT_GE(users, 3);
}

TEST(Island, HasAHeroTerrainOceanAndLights) {
  const Scene& scene = island();
  std::vector<uint32_t> counts = scene.instanceCountPerObject();
  bool hero = false, terrain = false, ocean = false;
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    uint64_t triangles = 0;
    for (int32_t m : scene.objects[o].meshes) triangles += scene.meshes[m].triangleCount();
    const std::string& name = scene.objects[o].name;
    if (name == "banyan") {
      hero = true;
      EXPECT_GT(triangles, 300000u);
      EXPECT_GE(counts[o], 1u);
      EXPECT_LE(counts[o], 3u);
    }
    if (name == "island-terrain") {
      terrain = true;
      EXPECT_EQ(counts[o], 1u);
      EXPECT_GT(triangles, 1000000u);
      const Mesh& m = scene.meshes[scene.objects[o].meshes[0]];
      EXPECT_FALSE(m.uvs.empty());
      EXPECT_FALSE(m.normals.empty());
      const Material& mat = scene.materials[m.material];
      ASSERT_NE(mat.baseColorTexture, kNoTexture);
      EXPECT_GE(scene.textures[mat.baseColorTexture].width, 1024);
    }
    if (name == "ocean") {
      ocean = true;
      const Material& water = scene.materials[scene.meshes[scene.objects[o].meshes[0]].material];
      EXPECT_EQ(water.transmission, 1.0f);
      EXPECT_FLOAT_EQ(water.ior, 1.33f);
      EXPECT_GT(water.roughness, 0.0f);  // rough, so light samples reach the sea (see island.cpp)
    }
  }
  EXPECT_TRUE(hero);
  EXPECT_TRUE(terrain);
  EXPECT_TRUE(ocean);
  SceneSummary s = summarize(scene);
  EXPECT_EQ(s.suns, 1u);
  EXPECT_EQ(s.environments, 1u);
  EXPECT_GE(s.emissiveMeshes, 3u);
  EXPECT_LT(s.emissiveTriangles, 5000u);  // small lanterns and a campfire
  EXPECT_GE(s.objects, 20u);
}

TEST(Island, ScaleOneStaysModest) {
  SceneSummary s = describeBuiltin(parseBuiltinSpec("builtin:island"));
  EXPECT_GT(s.triangles, 1000000u);
  EXPECT_LT(s.triangles, 6000000u);  // a few million unique triangles at most
  EXPECT_GT(s.instancedTriangles, 50000000u);
  EXPECT_LT(s.memory.total(), uint64_t(1500) << 20);
}

TEST(Island, LargeScaleDescribesHugeContentQuickly) {
  auto start = std::chrono::steady_clock::now();
  BuiltinParams p;
  p.name = "island";
  p.scale = builtin::kIslandLargeScale;
  SceneSummary s = describeBuiltin(p);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(s.instancedTriangles, 10'000'000'000ull);
  EXPECT_GT(s.triangles, 100'000'000ull);
  EXPECT_LT(seconds, 2.0);
  // Far beyond the large scale the description still answers at once.
  p.scale = 1e6;
  start = std::chrono::steady_clock::now();
  SceneSummary huge = describeBuiltin(p);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(huge.instancedTriangles, s.instancedTriangles);
  EXPECT_LT(seconds, 2.0);
}

TEST(Island, ScaleGrowsInstancesAndShrinksToATinyScene) {
  SceneSummary tiny = describeBuiltin(parseBuiltinSpec("builtin:island?scale=0.1"));
  SceneSummary one = describeBuiltin(parseBuiltinSpec("builtin:island"));
  SceneSummary four = describeBuiltin(parseBuiltinSpec("builtin:island?scale=4"));
  EXPECT_LT(tiny.instances, one.instances);
  EXPECT_LT(one.instances, four.instances);
  EXPECT_LT(tiny.triangles, one.triangles);
  EXPECT_LT(one.triangles, four.triangles);
  EXPECT_NEAR(double(four.instances) / double(one.instances), 4.0, 0.2);
  // Every species keeps at least one instance at tiny scales.
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.001"));
  std::map<std::string, SpeciesStats> stats = speciesStats(scene);
  EXPECT_GE(stats.size(), 8u);
  for (const auto& [name, st] : stats) EXPECT_GE(st.instances, 1u) << name;
}

TEST(Island, InstancesStandOnLandAndSpreadOverTheIsland) {
  const Scene& scene = island();
  std::map<std::string, Box3f> extent;
  for (const Instance& inst : scene.instances) {
    const std::string& name = scene.objects[inst.object].name;
    size_t slash = name.find('/');
    if (slash == std::string::npos) continue;
    extent[name.substr(0, slash)].extend(inst.transform.t);
  }
  for (const char* spread : {"grass", "tree", "rock", "palm"}) {
    ASSERT_TRUE(extent.count(spread)) << spread;
    Vec3f size = extent[spread].size();
    EXPECT_GT(size.x, 400) << spread;  // across most of a ~900 m island
    EXPECT_GT(size.z, 400) << spread;
  }
  // Palms grow by the sea, trees inland and higher up.
  EXPECT_LT(extent["palm"].upper.y, 12);
  EXPECT_GT(extent["tree"].upper.y, 20);
  for (const auto& [name, box] : extent) EXPECT_GT(box.lower.y, -6) << name;
}

}  // namespace
}  // namespace ferry
