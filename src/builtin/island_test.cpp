// The island after Disney's Moana island: its 20 elements, each several
// meshes, with its own species in its own region; counts that `ferry info`
// gives without generating equal to what is generated; a scale knob that
// reaches 1e10 instanced triangles in its description.
#include "builtin/island.h"

#include <chrono>
#include <cmath>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "builtin/builtin.h"
#include "builtin/island_elements.h"
#include "builtin/island_shape.h"
#include "builtin/vegetation.h"
#include "material/models/dielectric.h"
#include "scene/memory_cost.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

using builtin::kIslandElements;

const Scene& island() {
  static const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island"));
  return scene;
}

const Scene& smallIsland() {
  static const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.1"));
  return scene;
}

std::string elementOf(const std::string& objectName) {
  return objectName.substr(0, objectName.find('/'));
}

struct ElementStats {
  uint64_t objects = 0, meshes = 0, triangles = 0, instances = 0, instancedTriangles = 0;
  uint64_t bytes = 0;  // unique geometry and instances, by the memory model
  uint64_t largestMeshBytes = 0;
  bool operator==(const ElementStats&) const = default;
};

// From the plan's counts alone, as `ferry info` sees them.
std::map<std::string, ElementStats> describedElements(const builtin::ScenePlan& plan) {
  std::map<std::string, ElementStats> stats;
  std::vector<uint64_t> instances(plan.objects.size(), 0);
  for (const builtin::InstanceBatch& b : plan.batches) instances[size_t(b.object)] += b.count;
  for (size_t o = 0; o < plan.objects.size(); ++o) {
    ElementStats& s = stats[elementOf(plan.objects[o].name)];
    uint64_t triangles = 0;
    for (int32_t m : plan.objects[o].meshes) {
      const builtin::MeshRecipe& r = plan.meshes[size_t(m)];
      uint64_t bytes =
          meshCost(r.counts.vertices, r.counts.triangles, r.hasNormals, r.hasUvs).total();
      s.bytes += bytes;
      s.largestMeshBytes = std::max(s.largestMeshBytes, bytes);
      triangles += r.counts.triangles;
      ++s.meshes;
    }
    ++s.objects;
    s.triangles += triangles;
    s.instances += instances[o];
    s.instancedTriangles += instances[o] * triangles;
    s.bytes += instanceCost(instances[o]).total();
  }
  return stats;
}

// From the generated scene.
std::map<std::string, ElementStats> generatedElements(const Scene& scene) {
  std::map<std::string, ElementStats> stats;
  std::vector<uint32_t> counts = scene.instanceCountPerObject();
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    ElementStats& s = stats[elementOf(scene.objects[o].name)];
    uint64_t triangles = 0;
    for (int32_t m : scene.objects[o].meshes) {
      uint64_t bytes = meshCost(scene.meshes[size_t(m)]).total();
      s.bytes += bytes;
      s.largestMeshBytes = std::max(s.largestMeshBytes, bytes);
      triangles += scene.meshes[size_t(m)].triangleCount();
      ++s.meshes;
    }
    ++s.objects;
    s.triangles += triangles;
    s.instances += counts[o];
    s.instancedTriangles += counts[o] * triangles;
    s.bytes += instanceCost(counts[o]).total();
  }
  return stats;
}

bool isTerrainElement(const std::string& e) {
  return e == "isMountainA" || e == "isMountainB" || e == "isBeach" || e == "isDunesA" ||
         e == "isDunesB" || e == "isCoastline" || e == "isLavaRocks" || e == "isCoral" ||
         e == "osOcean";
}

TEST(Island, IsMoanasTwentyElementsEachOfSeveralMeshes) {
  std::map<std::string, ElementStats> stats = describedElements(builtin::planIsland(1, 1));
  std::set<std::string> expected(kIslandElements.begin(), kIslandElements.end());
  ASSERT_EQ(expected.size(), 20u);
  std::set<std::string> names;
  for (const auto& [name, s] : stats) names.insert(name);
  EXPECT_EQ(names, expected);  // every object belongs to one of them, named "<element>/..."
  for (const auto& [name, s] : stats) {
    SCOPED_TRACE(name);
    EXPECT_GE(s.meshes, 2u);
    EXPECT_GE(s.instances, 1u);
    if (isTerrainElement(name)) {
      EXPECT_GE(s.meshes, 5u);  // the ground in pieces, set pieces
    }
  }
}

TEST(Island, NoMeshHoldsMuchOfTheIsland) {
  // The previous island's terrain was one mesh of 61% of its bytes; Moana's
  // ground is its elements' meshes.
  std::map<std::string, ElementStats> stats = describedElements(builtin::planIsland(1, 1));
  uint64_t total = 0, largest = 0, terrain = 0;
  for (const auto& [name, s] : stats) {
    total += s.bytes;
    largest = std::max(largest, s.largestMeshBytes);
    if (isTerrainElement(name)) terrain += s.bytes;
  }
  EXPECT_LT(double(largest), 0.15 * double(total));
  // Neither the terrain elements nor the plant elements dominate.
  EXPECT_GT(double(terrain), 0.3 * double(total));
  EXPECT_LT(double(terrain), 0.8 * double(total));
}

// Instances per element follow the element table (island_elements.cpp): its
// species at `scale`, a terrain element's base object, isIronwoodA1's giant trees
// and the beach's campfire and four lanterns.
TEST(Island, InstanceCountsFollowTheElementTable) {
  for (double scale : {0.05, 0.1, 1.0, 4.0}) {
    SCOPED_TRACE(scale);
    std::map<std::string, uint64_t> expected;
    for (const char* e : kIslandElements) expected[e] = isTerrainElement(e) ? 1 : 0;
    for (const builtin::ElementSpecies& sp : builtin::islandSpecies())
      expected[sp.element] += builtin::scaledCount(sp.count, scale);
    expected["isIronwoodA1"] += builtin::scaledCount(4, scale);
    expected["isBeach"] += 5;
    std::map<std::string, ElementStats> stats = describedElements(builtin::planIsland(scale, 1));
    for (const auto& [name, n] : expected) EXPECT_EQ(stats[name].instances, n) << name;
  }
}

TEST(Island, InfoCountsEqualWhatIsGeneratedPerElement) {
  std::map<std::string, ElementStats> described =
      describedElements(builtin::planIsland(0.1, BuiltinParams{}.seed));
  std::map<std::string, ElementStats> generated = generatedElements(smallIsland());
  ASSERT_EQ(described.size(), generated.size());
  for (const auto& [name, s] : described) EXPECT_EQ(s, generated[name]) << name;
}

TEST(Island, EachElementsPlantsGrowInItsOwnRegion) {
  const Scene& scene = smallIsland();
  builtin::IslandShape shape(BuiltinParams{}.seed);
  std::map<std::string, builtin::Region> regions;
  for (const builtin::ElementSpecies& sp : builtin::islandSpecies())
    regions[sp.element + "/" + sp.name] = sp.region;
  std::map<std::string, uint64_t> checked;
  std::map<std::string, Box3f> extent;
  for (const Instance& inst : scene.instances) {
    const std::string& name = scene.objects[size_t(inst.object)].name;
    auto it = regions.find(name.substr(0, name.rfind('/')));
    if (it == regions.end()) continue;  // base objects, the giant trees, campfire and lanterns
    Vec2f p{inst.transform.t.x, inst.transform.t.z};
    EXPECT_TRUE(shape.inRegion(it->second, p, shape.where(p.x, p.y))) << name;
    ++checked[elementOf(name)];
    extent[elementOf(name)].extend(inst.transform.t);
  }
  EXPECT_EQ(checked.size(), 20u - 1u);  // every element but the ocean scatters something
  // What grows varies by region: the reef is under water, the beach's
  // species stay on the south shore, the mountains' on their slopes.
  EXPECT_LT(extent["isCoral"].upper.y, 0);
  EXPECT_GT(extent["isBeach"].lower.z, 0);  // the beach faces +z
  EXPECT_LT(extent["isMountainA"].center().z, 0);
  EXPECT_GT(extent["isMountainA"].upper.y, 40);
}

TEST(Island, LeavesAreAlphaCutCardsSharingOneTexture) {
  const Scene& scene = island();
  int32_t leafTexture = kNoTexture;
  for (const Material& m : scene.materials)
    if (m.name == "leaves") leafTexture = m.alphaTexture;
  ASSERT_NE(leafTexture, kNoTexture);
  const Texture& t = scene.textures[size_t(leafTexture)];
  size_t holes = 0, solid = 0;
  for (size_t i = 3; i < t.rgba.size(); i += 4) (t.rgba[i] < 128 ? holes : solid)++;
  EXPECT_GT(holes, t.texelCount() / 10);
  EXPECT_GT(solid, t.texelCount() / 10);
  // Trees, bushes and flowers all use it.
  int users = 0;
  for (const Mesh& m : scene.meshes)
    if (scene.materials[size_t(m.material)].alphaTexture == leafTexture) ++users;
  EXPECT_GE(users, 3);
}

TEST(Island, HasAGiantTreeTexturedGroundOceanAndLights) {
  const Scene& scene = island();
  std::vector<uint32_t> counts = scene.instanceCountPerObject();
  bool giant = false, ground = false, ocean = false;
  for (size_t o = 0; o < scene.objects.size(); ++o) {
    uint64_t triangles = 0;
    for (int32_t m : scene.objects[o].meshes) triangles += scene.meshes[size_t(m)].triangleCount();
    const std::string& name = scene.objects[o].name;
    if (name == "isIronwoodA1/ironwood") {
      giant = true;
      EXPECT_GT(triangles, 300000u);
      EXPECT_EQ(counts[o], 4u);
    }
    if (name == "isDunesA/base") {
      ground = true;
      EXPECT_EQ(counts[o], 1u);
      const Mesh& m = scene.meshes[size_t(scene.objects[o].meshes[0])];
      EXPECT_FALSE(m.uvs.empty());
      EXPECT_FALSE(m.normals.empty());
      const Material& mat = scene.materials[size_t(m.material)];
      ASSERT_NE(mat.baseColorTexture, kNoTexture);
      EXPECT_GE(scene.textures[size_t(mat.baseColorTexture)].width, 1024);
    }
    for (int32_t m : scene.objects[o].meshes) {
      if (scene.meshes[size_t(m)].name != "osOcean/water-0") continue;
      ocean = true;
      const Material& water = scene.materials[size_t(scene.meshes[size_t(m)].material)];
      const auto* surface = dynamic_cast<const DielectricModel*>(water.model.get());
      ASSERT_NE(surface, nullptr);
      EXPECT_FLOAT_EQ(surface->ior, 1.33f);
      // Rough, so light samples reach the sea (see island.cpp).
      EXPECT_GT(surface->roughness, 0.0f);
    }
  }
  EXPECT_TRUE(giant);
  EXPECT_TRUE(ground);
  EXPECT_TRUE(ocean);
  SceneSummary s = summarize(scene);
  EXPECT_EQ(s.suns, 1u);
  EXPECT_EQ(s.environments, 1u);
  EXPECT_GE(s.emissiveMeshes, 3u);
  EXPECT_LT(s.emissiveTriangles, 5000u);  // small lanterns and a campfire
}

TEST(Island, ScaleOneStaysModest) {
  SceneSummary s = describeBuiltin(parseBuiltinSpec("builtin:island"));
  EXPECT_GT(s.triangles, 1000000u);
  EXPECT_LT(s.triangles, 4000000u);  // a few million unique triangles at most
  EXPECT_GT(s.instancedTriangles, 200000000u);
  EXPECT_LT(s.memory.total(), uint64_t(400) << 20);
  // Ratios near the published Moana figures (docs/scenes.md): about 0.075
  // instances per unique triangle and 316 instanced per unique triangle.
  double instancesPerTriangle = double(s.instances) / double(s.triangles);
  double instancedPerUnique = double(s.instancedTriangles) / double(s.triangles);
  EXPECT_GT(instancesPerTriangle, 0.05);
  EXPECT_LT(instancesPerTriangle, 0.11);
  EXPECT_GT(instancedPerUnique, 150);
  EXPECT_LT(instancedPerUnique, 500);
}

TEST(Island, SmallScalesStaySmall) {
  SceneSummary s = describeBuiltin(parseBuiltinSpec("builtin:island?scale=0.1"));
  EXPECT_LT(s.triangles, 1000000u);
}

TEST(Island, LargeScaleDescribesHugeContentQuickly) {
  auto start = std::chrono::steady_clock::now();
  BuiltinParams p;
  p.name = "island";
  p.scale = builtin::kIslandLargeScale;
  SceneSummary s = describeBuiltin(p);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(s.instancedTriangles, 10'000'000'000ull);
  EXPECT_GT(s.triangles, 50'000'000ull);
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
  // Every element keeps its species at tiny scales, each with an instance.
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:island?scale=0.001"));
  std::map<std::string, ElementStats> stats = generatedElements(scene);
  EXPECT_EQ(stats.size(), 20u);
  std::vector<uint32_t> counts = scene.instanceCountPerObject();
  for (size_t o = 0; o < scene.objects.size(); ++o)
    EXPECT_GE(counts[o], 1u) << scene.objects[o].name;
}

}  // namespace
}  // namespace ferry
