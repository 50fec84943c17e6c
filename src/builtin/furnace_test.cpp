#include "builtin/furnace.h"

#include <gtest/gtest.h>

#include "builtin/builtin.h"
#include "material/models/diffuse.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

TEST(Furnace, WhiteSphereInAWhiteEnvironment) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:furnace"));
  ASSERT_EQ(scene.meshes.size(), 1u);
  const Mesh& sphere = scene.meshes[0];
  const Material& m = scene.materials[sphere.material];
  EXPECT_EQ(m.baseColor, Vec3f(builtin::kFurnaceAlbedo));
  // Lambertian.
  const auto* diffuse = dynamic_cast<const DiffuseModel*>(m.model.get());
  ASSERT_NE(diffuse, nullptr);
  EXPECT_EQ(diffuse->sigmaDegrees, 0.0f);
  EXPECT_FALSE(m.isEmissive());
  EXPECT_EQ(scene.environment.color, Vec3f(1, 1, 1));
  EXPECT_EQ(scene.environment.image, nullptr);
  EXPECT_TRUE(scene.suns.empty());
  ASSERT_EQ(sphere.normals.size(), sphere.positions.size());
  for (size_t v = 0; v < sphere.positions.size(); ++v) {
    EXPECT_NEAR(length(sphere.positions[v]), 1.0f, 1e-5f);
    EXPECT_NEAR(dot(sphere.normals[v], sphere.positions[v]), 1.0f, 1e-5f);
  }
  // Triangles wind outwards, matching the normals.
  for (const Vec3i& t : sphere.indices) {
    Vec3f p0 = sphere.positions[t.x], p1 = sphere.positions[t.y], p2 = sphere.positions[t.z];
    Vec3f n = cross(p1 - p0, p2 - p0);
    ASSERT_GT(length(n), 0);
    EXPECT_GT(dot(n, p0 + p1 + p2), 0);
  }
  SceneSummary s = summarize(scene);
  EXPECT_EQ(s.bounds.lower, Vec3f(-1, -1, -1));
  EXPECT_EQ(s.bounds.upper, Vec3f(1, 1, 1));
  EXPECT_GT(s.triangles, 5000u);
  const CameraView& view = scene.view("default");
  EXPECT_GT(length(view.from), 2.0f);
  EXPECT_EQ(view.at, Vec3f(0, 0, 0));
}

TEST(Furnace, ScaleRefinesTheSphere) {
  SceneSummary a = describeBuiltin(parseBuiltinSpec("builtin:furnace?scale=0.1"));
  SceneSummary b = describeBuiltin(parseBuiltinSpec("builtin:furnace?scale=4"));
  EXPECT_LT(a.triangles, b.triangles);
  EXPECT_EQ(a.instances, 1u);
  EXPECT_EQ(b.instances, 1u);
}

}  // namespace
}  // namespace ferry
