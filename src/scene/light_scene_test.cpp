#include "scene/light_scene.h"

#include <gtest/gtest.h>

#include "builtin/builtin.h"
#include "core/random.h"
#include "render/lights.h"

namespace ferry {
namespace {

float uniform(uint32_t a, uint32_t b) {
  return random01(RandomKey{a, b, 0, 9}, RandomDim::OwnerPick);
}

}  // namespace

TEST(LightScene, SamplesExactlyLikeTheWholeScene) {
  for (const char* spec : {"builtin:cornell", "builtin:island?scale=0.05"}) {
    SCOPED_TRACE(spec);
    Scene scene = generateBuiltin(parseBuiltinSpec(spec));
    Scene lights = lightScene(scene);
    lights.validate();
    EXPECT_LT(lights.meshes.size(), scene.meshes.size());
    LightSampler whole(scene), small(lights);
    ASSERT_GT(whole.emissiveTriangleCount(), 0u);
    ASSERT_EQ(whole.emissiveTriangleCount(), small.emissiveTriangleCount());
    const Box3f b = scene.worldBounds();
    for (uint32_t k = 0; k < 20000; ++k) {
      Vec3f p = b.lower + b.size() * Vec3f(uniform(k, 0), uniform(k, 1), uniform(k, 2));
      Vec3f n = normalize(Vec3f(uniform(k, 3), uniform(k, 4), uniform(k, 5)) - Vec3f(0.5f));
      bool twoSided = uniform(k, 6) < 0.2f;
      LightSample a, c;
      bool ra = whole.sample(p, n, twoSided, uniform(k, 7), {uniform(k, 8), uniform(k, 9)}, a);
      bool rc = small.sample(p, n, twoSided, uniform(k, 7), {uniform(k, 8), uniform(k, 9)}, c);
      ASSERT_EQ(ra, rc) << k;
      if (!ra) continue;
      ASSERT_TRUE(a.direction == c.direction) << k;
      ASSERT_EQ(a.distance, c.distance) << k;
      ASSERT_TRUE(a.radiance == c.radiance) << k;
      ASSERT_EQ(a.pdf, c.pdf) << k;
      ASSERT_TRUE(whole.background(n) == small.background(n));
    }
  }
}

}  // namespace ferry
