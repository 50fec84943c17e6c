// Light selection for a surface that only reflects (LightSampler::sample's
// `facing`): suns below its horizon are never chosen, the estimate of the
// light arriving stays unbiased, and the emitters' densities do not change.
// LightChoice: Near prefers the emitter near the point, Power chooses by
// power alone wherever the point is.
#include "render/lights.h"

#include <gtest/gtest.h>

#include <cmath>

#include "render/render_test_util.h"

namespace ferry {
namespace {

// Two suns, one 60 degrees from the normal +y and one below the horizon,
// and a constant sky; no emitters.
Scene distantLights() {
  Scene scene;
  SunLight above;
  above.direction = normalize(Vec3f{std::sqrt(3.0f), 1, 0});  // 60 degrees from +y
  above.irradiance = Vec3f(3);
  SunLight below;
  below.direction = normalize(Vec3f{0, -1, 1});
  below.irradiance = Vec3f(5);
  scene.suns = {above, below};
  scene.environment.color = Vec3f(0.5f);
  return scene;
}

// The unoccluded irradiance at a point with normal +y, estimated from light
// samples (radiance cos / pdf, nothing from below the horizon), and how
// often the sun below was chosen.
void estimate(const LightSampler& lights, bool facing, double& irradiance, int& belowChosen) {
  const Vec3f n{0, 1, 0};
  const Frame frame(n);
  testing::TestRng rng(7);
  double sum = 0;
  belowChosen = 0;
  constexpr int kSamples = 400000;
  for (int i = 0; i < kSamples; ++i) {
    LightSample ls;
    if (!lights.sample({0, 0, 0}, frame, false, rng.uniform(), {rng.uniform(), rng.uniform()}, ls,
                       facing ? n : Vec3f(0)))
      continue;
    const float cosine = dot(ls.direction, n);
    if (cosine < -0.5f) ++belowChosen;
    if (cosine > 0) sum += double(ls.radiance.x) * cosine / ls.pdf;
  }
  irradiance = sum / kSamples;
}

TEST(Lights, ASurfaceNeverChoosesASunBelowItsHorizonAndStaysUnbiased) {
  const Scene scene = distantLights();
  const LightSampler lights(scene);
  // 3 cos 60 from the sun above, 0.5 pi from the sky.
  const double expected = 3 * 0.5 + 0.5 * kPi;
  double plain = 0, facing = 0;
  int belowPlain = 0, belowFacing = 0;
  estimate(lights, false, plain, belowPlain);
  estimate(lights, true, facing, belowFacing);
  EXPECT_NEAR(plain, expected, 0.01 * expected);
  EXPECT_NEAR(facing, expected, 0.01 * expected);
  EXPECT_GT(belowPlain, 100000);  // without `facing`: by weight, more than half
  EXPECT_EQ(belowFacing, 0);
}

TEST(Lights, NoDistantLightAboveMeansNoSample) {
  Scene scene;
  SunLight below;
  below.direction = Vec3f{0, -1, 0};
  scene.suns = {below};
  const LightSampler lights(scene);
  LightSample ls;
  EXPECT_TRUE(lights.sample({0, 0, 0}, Frame(Vec3f{0, 1, 0}), false, 0.5f, {0.5f, 0.5f}, ls));
  EXPECT_FALSE(lights.sample({0, 0, 0}, Frame(Vec3f{0, 1, 0}), false, 0.5f, {0.5f, 0.5f}, ls,
                             Vec3f{0, 1, 0}));
  // A surface that transmits takes light from below: `facing` is not given.
  EXPECT_TRUE(lights.sample({0, 0, 0}, Frame(Vec3f{0, 1, 0}), true, 0.5f, {0.5f, 0.5f}, ls));
}

// Two emissive quads facing down: a dim one (power 1) above the point and a
// bright one (power 4) far away. Near chooses the dim one mostly; Power
// chooses the bright one 4 times in 5, as pbrt's "power" strategy does.
TEST(Lights, PowerChoiceFollowsPowerAloneNearFollowsDistance) {
  Scene scene;
  Material dim, bright;
  dim.emission = Vec3f(1);
  bright.emission = Vec3f(4);
  const int32_t d = scene.addMaterial(dim), b = scene.addMaterial(bright);
  scene.addSingleInstanceMesh(testing::makeQuad({-0.5f, 1, 0.5f}, {0, 0, -1}, {1, 0, 0}, d));
  scene.addSingleInstanceMesh(testing::makeQuad({19.5f, 1, 0.5f}, {0, 0, -1}, {1, 0, 0}, b));
  for (const LightChoice choice : {LightChoice::Near, LightChoice::Power}) {
    const LightSampler lights(scene, choice);
    testing::TestRng rng(3);
    int brightChosen = 0, samples = 0;
    for (int i = 0; i < 20000; ++i) {
      LightSample ls;
      if (!lights.sample({0, 0, 0}, Frame(Vec3f{0, 1, 0}), false, rng.uniform(),
                         {rng.uniform(), rng.uniform()}, ls))
        continue;
      ++samples;
      brightChosen += ls.direction.x > 0.5f;
    }
    ASSERT_GT(samples, 19000);
    const double share = double(brightChosen) / samples;
    if (choice == LightChoice::Power)
      EXPECT_NEAR(share, 0.8, 0.015);
    else
      EXPECT_LT(share, 0.05);
  }
}

}  // namespace
}  // namespace ferry
