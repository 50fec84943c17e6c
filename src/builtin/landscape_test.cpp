#include "builtin/landscape.h"

#include <set>

#include <gtest/gtest.h>

#include "builtin/builtin.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

const Scene& landscape() {
  static const Scene scene = generateBuiltin(parseBuiltinSpec("builtin:landscape"));
  return scene;
}

TEST(Landscape, HasHundredsOfUniquePlantMeshes) {
  const Scene& scene = landscape();
  size_t plantMeshes = 0;
  for (const Object& o : scene.objects)
    if (o.name.find('/') != std::string::npos) plantMeshes += o.meshes.size();
  EXPECT_GE(plantMeshes, 300u);
  std::vector<uint32_t> counts = scene.instanceCountPerObject();
  for (size_t o = 0; o < scene.objects.size(); ++o)
    if (scene.objects[o].name.find('/') != std::string::npos) {
      EXPECT_GE(counts[o], 1u) << scene.objects[o].name;
    }
}

TEST(Landscape, HasTensOfThousandsOfInstances) {
  SceneSummary s = summarize(landscape());
  EXPECT_GE(s.instances, 10000u);
  EXPECT_LT(s.instances, 100000u);
  EXPECT_LT(s.triangles, 5000000u);
  EXPECT_GT(s.instancedTriangles, s.triangles * 10);
  EXPECT_EQ(s.suns, 1u);
  EXPECT_EQ(s.environments, 1u);
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
  // The eye is a person's height above the terrain under it.
  const Mesh* terrain = nullptr;
  for (const Mesh& m : scene.meshes)
    if (m.name == "landscape-terrain") terrain = &m;
  ASSERT_NE(terrain, nullptr);
  float nearest = 1e30f, groundY = 0;
  for (const Vec3f& p : terrain->positions) {
    float d = (p.x - path.from.x) * (p.x - path.from.x) + (p.z - path.from.z) * (p.z - path.from.z);
    if (d < nearest) nearest = d, groundY = p.y;
  }
  EXPECT_NEAR(path.from.y - groundY, 1.7f, 0.5f);
}

TEST(Landscape, ScaleGrowsInstancesNotVariants) {
  SceneSummary one = describeBuiltin(parseBuiltinSpec("builtin:landscape"));
  SceneSummary three = describeBuiltin(parseBuiltinSpec("builtin:landscape?scale=3"));
  EXPECT_EQ(one.objects, three.objects);
  EXPECT_NEAR(double(three.instances) / double(one.instances), 3.0, 0.1);
  EXPECT_GT(three.triangles, one.triangles);  // a finer terrain
}

}  // namespace
}  // namespace ferry
