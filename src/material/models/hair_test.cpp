// The hair model (material/models/hair.h) against what Chiang et al.'s model
// promises: a lossless fibre (sigma_a 0) scatters all it receives (its
// integral over the sphere is 1: the white furnace), pbrt's sampling draws it
// exactly (every sample's weight f cos / pdf is 1), the density sampling
// reports is the one pdf() gives and integrates to 1, and an absorbing
// fibre never returns more than it receives.
#include "material/models/hair.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"

namespace ferry {
namespace {

struct Uniform {
  uint32_t state;
  float operator()() {
    state = hashMix(state + 0x9e3779b9u);
    return float(state >> 8) * (1.0f / 16777216.0f);
  }
};

Vec3f uniformSphere(float u, float v) {
  const float z = 1 - 2 * u, r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2 * kPi * v;
  return {r * std::cos(phi), r * std::sin(phi), z};
}

TEST(Hair, ALosslessFibreScattersEverythingItReceives) {
  Uniform rng{5};
  for (float betaM : {0.1f, 0.3f, 0.7f})
    for (float betaN : {0.2f, 0.5f, 0.9f}) {
      // Over wo and h: the furnace (mean of f cos / uniform pdf) and the
      // density's integral.
      double albedo = 0, density = 0;
      const int n = 200000;
      for (int k = 0; k < n; ++k) {
        const Bsdf bsdf = hairBsdf(-1 + 2 * rng(), 1.55f, Vec3f(0), betaM, betaN, 2);
        const Vec3f wo = uniformSphere(rng(), rng()), wi = uniformSphere(rng(), rng());
        albedo += bsdf.eval(wo, wi).y * 4 * kPi;
        density += bsdf.pdf(wo, wi) * 4 * kPi;
      }
      EXPECT_NEAR(albedo / n, 1, 0.03) << "beta_m " << betaM << " beta_n " << betaN;
      EXPECT_NEAR(density / n, 1, 0.03) << "beta_m " << betaM << " beta_n " << betaN;
    }
}

TEST(Hair, SamplingALosslessFibreIsExactAndConsistent) {
  Uniform rng{9};
  int drawn = 0;
  for (int k = 0; k < 20000; ++k) {
    const Bsdf bsdf = hairBsdf(-1 + 2 * rng(), 1.55f, Vec3f(0), 0.3f, 0.3f, 2);
    const Vec3f wo = uniformSphere(rng(), rng());
    BsdfSample s;
    if (!bsdf.sample(wo, rng(), {rng(), rng()}, s)) continue;
    ++drawn;
    EXPECT_NEAR(length(s.wi), 1, 1e-4f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight[c], 1, 2e-3f) << k;
    EXPECT_NEAR(s.pdf, bsdf.pdf(wo, s.wi), 1e-3f * std::max(1.0f, s.pdf)) << k;
  }
  EXPECT_GT(drawn, 19000);
}

TEST(Hair, AnAbsorbingFibreReturnsLessAndMelaninDarkensIt) {
  Uniform rng{13};
  auto albedo = [&](Vec3f sigmaA) {
    Uniform r = rng;
    double sum = 0;
    const int n = 100000;
    for (int k = 0; k < n; ++k) {
      const Bsdf bsdf = hairBsdf(-1 + 2 * r(), 1.55f, sigmaA, 0.3f, 0.3f, 2);
      sum += bsdf.eval(uniformSphere(r(), r()), uniformSphere(r(), r())).x * 4 * kPi;
    }
    return sum / n;
  };
  const double light = albedo(hairSigmaAFromMelanin(0.3f, 0));
  const double dark = albedo(hairSigmaAFromMelanin(8, 0));
  EXPECT_LT(light, 0.97);
  EXPECT_LT(dark, light);
  EXPECT_GT(dark, 0.02);  // the surface reflection (R) stays
  // pbrt's conversion from a colour: a paler colour absorbs less.
  const Vec3f pale = hairSigmaAFromColor(Vec3f(0.9f), 0.3f),
              deep = hairSigmaAFromColor(Vec3f(0.2f), 0.3f);
  EXPECT_LT(pale.x, deep.x);
  EXPECT_EQ(hairSigmaAFromColor(Vec3f(1), 0.3f), Vec3f(0));
}

TEST(Hair, TheModelReadsTheOffsetAcrossTheFibreFromV) {
  HairModel m;
  m.absorption = HairModel::Absorption::SigmaA;
  m.sigmaA = Vec3f(0.5f);
  const Vec3f wo = normalize(Vec3f(0.2f, 0.3f, 0.9f)), wi = normalize(Vec3f(-0.1f, -0.8f, 0.3f));
  const Vec3f edge = m.bsdfAt(Vec3f(1), {0, 0.05f}, {}).eval(wo, wi);
  const Vec3f centre = m.bsdfAt(Vec3f(1), {0, 0.5f}, {}).eval(wo, wi);
  EXPECT_NE(edge.x, centre.x);
  EXPECT_EQ(m.bsdf(Vec3f(1), {}).eval(wo, wi).x, centre.x);
}

}  // namespace
}  // namespace ferry
