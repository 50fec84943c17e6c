#include "builtin/cornell.h"

#include <gtest/gtest.h>

#include "builtin/builtin.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

const Mesh& meshNamed(const Scene& scene, const std::string& name) {
  for (const Mesh& m : scene.meshes)
    if (m.name == name) return m;
  throw std::runtime_error("no mesh " + name);
}

Vec3f geometricNormal(const Mesh& m, size_t t) {
  Vec3f p0 = m.positions[m.indices[t].x], p1 = m.positions[m.indices[t].y],
        p2 = m.positions[m.indices[t].z];
  return normalize(cross(p1 - p0, p2 - p0));
}

TEST(Cornell, ClassicBoxWithColouredWallsAndALight) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell"));
  const Material& left = scene.materials[meshNamed(scene, "left-wall").material];
  const Material& right = scene.materials[meshNamed(scene, "right-wall").material];
  EXPECT_GT(left.baseColor.x, 3 * left.baseColor.y);    // red
  EXPECT_GT(right.baseColor.y, 2 * right.baseColor.x);  // green
  for (const char* white : {"floor", "ceiling", "back-wall", "short-block", "tall-block"}) {
    Vec3f c = scene.materials[meshNamed(scene, white).material].baseColor;
    EXPECT_NEAR(c.x, c.y, 0.05f) << white;
  }
  SceneSummary s = summarize(scene);
  EXPECT_EQ(s.emissiveMeshes, 1u);
  EXPECT_EQ(s.emissiveTriangles, 2u);
  EXPECT_EQ(s.suns, 0u);
  EXPECT_EQ(s.environments, 0u);
  EXPECT_EQ(s.triangles, 2u * 5 + 2 * 10 + 2);  // five walls, two five-sided blocks, the light
  EXPECT_NEAR(s.bounds.upper.x, 556, 1e-3);
  EXPECT_NEAR(s.bounds.upper.y, 548.8, 1e-3);
  EXPECT_NEAR(s.bounds.upper.z, 559.2, 1e-3);
  EXPECT_EQ(scene.view("default").from, Vec3f(278, 273, -800));
}

TEST(Cornell, WallsFaceInwardBlocksOutwardLightDown) {
  Scene scene = generateBuiltin(parseBuiltinSpec("builtin:cornell?scale=2"));
  const Vec3f centre{278, 274, 280};
  for (const char* wall : {"floor", "ceiling", "back-wall", "left-wall", "right-wall"}) {
    const Mesh& m = meshNamed(scene, wall);
    EXPECT_EQ(m.triangleCount(), 8u) << wall;  // 2 x 2 cells
    for (size_t t = 0; t < m.triangleCount(); ++t)
      EXPECT_GT(dot(geometricNormal(m, t), centre - m.positions[m.indices[t].x]), 0) << wall;
  }
  const Mesh& light = meshNamed(scene, "light");
  for (size_t t = 0; t < light.triangleCount(); ++t) EXPECT_LT(geometricNormal(light, t).y, -0.99f);
  for (const char* block : {"short-block", "tall-block"}) {
    const Mesh& m = meshNamed(scene, block);
    Box3f b = m.bounds();
    Vec3f c = b.center();
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      Vec3f p = (m.positions[m.indices[t].x] + m.positions[m.indices[t].y] +
                 m.positions[m.indices[t].z]) /
                3.0f;
      EXPECT_GT(dot(geometricNormal(m, t), p - c), 0) << block << " triangle " << t;
    }
  }
}

}  // namespace
}  // namespace ferry
