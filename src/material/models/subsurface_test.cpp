// The subsurface model's surface (material/models/subsurface.h): a walk
// arriving from inside is mirrored back with the inside Fresnel reflectance
// or leaves by Sw, whose weights average to exactly what leaves (no light is
// made or lost at the surface); Sw's normalization is its cosine integral;
// and pbrt's diffuse-reflectance inversion is the inverse of the photon beam
// diffusion reflectance.
#include "material/models/subsurface.h"

#include <gtest/gtest.h>

#include <cmath>

#include "render/render_test_util.h"

namespace ferry {
namespace {

TEST(Subsurface, FromInsideAWalkIsMirroredOrLeavesWithAllItCarries) {
  const SubsurfaceModel model(1.33f, 0, Vec3f(1));
  const Bsdf bsdf = model.bsdf(Vec3f(1), {});
  EXPECT_TRUE(bsdf.transmits());
  for (float cosInside : {0.95f, 0.6f, 0.3f}) {
    const Vec3f wo{std::sqrt(1 - cosInside * cosInside), 0, -cosInside};
    const float reflectance = fresnelDielectric(cosInside, 1 / 1.33f);
    testing::TestRng rng(uint64_t(cosInside * 1000));
    auto u = [&] { return rng.uniform(); };
    constexpr int n = 200000;
    double weight = 0, mirrored = 0, worst = 0;
    for (int i = 0; i < n; ++i) {
      BsdfSample s;
      ASSERT_TRUE(bsdf.sample(wo, u(), {u(), u()}, s));
      weight += s.weight.x;
      if (s.delta) {
        mirrored += 1;
        EXPECT_LT(s.wi.z, 0);
        continue;
      }
      ASSERT_GT(s.wi.z, 0);
      // A leaving sample's weight is eval / pdf.
      const float pdf = bsdf.pdf(wo, s.wi);
      worst = std::max(worst, double(std::abs(s.weight.x - bsdf.eval(wo, s.wi).x / pdf)));
      EXPECT_NEAR(s.pdf, pdf, 1e-5f);
    }
    EXPECT_LT(worst, 1e-4);
    EXPECT_NEAR(mirrored / n, reflectance, 4 * std::sqrt(reflectance / n) + 1e-3) << cosInside;
    EXPECT_NEAR(weight / n, 1.0, 0.01) << cosInside;
  }
  // Beyond the critical angle every walk is mirrored back in.
  const Vec3f grazing{0.9f, 0, -std::sqrt(1 - 0.81f)};
  BsdfSample s;
  ASSERT_TRUE(bsdf.sample(grazing, 0.999f, {0.5f, 0.5f}, s));
  EXPECT_TRUE(s.delta);
}

TEST(Subsurface, ExitLobeIntegratesToOne) {
  // c = 1 - 2 x (the first Fresnel moment seen from outside).
  EXPECT_NEAR(subsurfaceExitNormalization(1.33f), 1 - 2 * 0.0329654f, 1e-4f);
  for (float ior : {1.2f, 1.33f, 1.5f}) {
    const float c = subsurfaceExitNormalization(ior);
    double integral = 0;
    constexpr int n = 4096;
    for (int i = 0; i < n; ++i) {
      const double mu = (i + 0.5) / n;  // cos: the hemisphere's integral is 2 pi mu dmu
      integral += 2 * kPi * mu * (1 - fresnelDielectric(float(mu), ior)) / (c * kPi) / n;
    }
    EXPECT_NEAR(integral, 1.0, 1e-3) << ior;
  }
}

TEST(Subsurface, DiffuseReflectanceInvertsThePhotonBeamDiffusionProfile) {
  float previous = -1;
  for (float albedo : {0.1f, 0.5f, 0.8f, 0.95f, 0.99f}) {
    const float r = photonBeamDiffusionReflectance(albedo, 0, 1.33f);
    EXPECT_GT(r, previous) << albedo;
    EXPECT_LT(r, 1.0f);
    previous = r;
    const Vec3f back = subsurfaceAlbedoFromReflectance(Vec3f(r), 0, 1.33f);
    EXPECT_NEAR(back.x, albedo, 2e-3f) << albedo;
  }
  EXPECT_EQ(subsurfaceAlbedoFromReflectance(Vec3f(0), 0, 1.33f).x, 0);
}

}  // namespace
}  // namespace ferry
