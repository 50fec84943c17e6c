#include "material/models/layered.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"

namespace ferry {
namespace {

Vec3f direction(float cosTheta, float phi) {
  const float s = std::sqrt(std::max(0.0f, 1 - cosTheta * cosTheta));
  return {s * std::cos(phi), s * std::sin(phi), cosTheta};
}

float uniform(uint32_t i, uint32_t d) {
  return float(hashMix(hashCombine(i, d)) >> 8) * 0x1p-24f;
}

// The mean of sample()'s weights: the share of light reflected towards wo.
double albedoBySampling(const LayeredLobe& lobe, Vec3f wo, uint32_t n) {
  double sum = 0;
  for (uint32_t i = 0; i < n; ++i) {
    BsdfSample bs;
    if (lobe.sample(wo, uniform(i, 1), {uniform(i, 2), uniform(i, 3)}, bs)) sum += bs.weight.y;
  }
  return sum / n;
}

// The same share by integrating eval() over the hemisphere (uniformly).
double albedoByEval(const LayeredLobe& lobe, Vec3f wo, uint32_t n) {
  double sum = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Vec3f wi = direction(uniform(i, 4), 2 * kPi * uniform(i, 5));
    sum += lobe.eval(wo, wi).y * (2 * kPi);
  }
  return sum / n;
}

// A white base under a smooth lossless interface, no slab: every photon
// leaves again (a white furnace). A rough interface loses what its single
// microfacet scattering loses at each crossing, and never gains.
TEST(LayeredLobe, WhiteBaseUnderALosslessInterfaceReflectsEverything) {
  for (float alpha : {0.0f, 0.3f}) {
    LayeredLobe lobe;
    lobe.base = Vec3f(1);
    lobe.alpha = alpha;
    lobe.thickness = 1e-6f;
    lobe.maxDepth = 1000;
    for (float cosTheta : {0.9f, 0.5f, 0.2f}) {
      const Vec3f wo = direction(cosTheta, 0.3f);
      const double albedo = albedoBySampling(lobe, wo, 200000);
      if (alpha == 0)
        EXPECT_NEAR(albedo, 1.0, 0.01) << cosTheta;
      else
        EXPECT_LT(albedo, 1.0) << cosTheta;
    }
  }
}

// eval() and sample() estimate the same BSDF: sample()'s albedo is eval()'s
// plus, under a smooth interface, its mirror reflection F(wo), which eval()
// leaves to sample(). Under a rough one eval() weighs its two ways out of the
// slab by MIS; each weight takes the other way's density of the same
// direction (pbrt-v4 takes the reverse density for the second, which reads
// 7 % high here and +4 % against pbrt-v4's own render of a rough coat).
TEST(LayeredLobe, EvalAndSampleAgree) {
  LayeredLobe grey;
  grey.base = Vec3f(0.7f);
  LayeredLobe foggy = grey;
  foggy.albedo = Vec3f(0.8f);
  foggy.thickness = 0.5f;
  foggy.g = 0.4f;
  LayeredLobe metal = grey;
  metal.baseAlpha = 0.2f;
  metal.base = Vec3f(0.9f);
  LayeredLobe roughGrey = grey, roughFoggy = foggy, roughMetal = metal;
  roughGrey.alpha = roughFoggy.alpha = roughMetal.alpha = 0.3f;
  for (const LayeredLobe* lobe : {&grey, &foggy, &metal, &roughGrey, &roughFoggy, &roughMetal}) {
    const Vec3f wo = direction(0.7f, 1.0f);
    const double sampled = albedoBySampling(*lobe, wo, 200000);
    const double mirror = lobe->alpha == 0 ? fresnelDielectric(0.7f, 1.5f) : 0.0f;
    const double evaluated = albedoByEval(*lobe, wo, 400000) + mirror;
    EXPECT_NEAR(sampled, evaluated, 0.02 * evaluated) << lobe->alpha << " " << lobe->baseAlpha;
    EXPECT_LT(sampled, 1.0);
  }
  // Trapped light: 0.7 under a smooth coat of index 1.5 reflects about half.
  const double a = albedoBySampling(grey, direction(1, 0), 200000);
  EXPECT_GT(a, 0.40);
  EXPECT_LT(a, 0.60);
}

// One (wo, wi) always gets one value: the walk's numbers are a hash of the
// directions, so images do not depend on who evaluates it or when.
TEST(LayeredLobe, EstimatesAreFunctionsOfTheirArguments) {
  LayeredLobe lobe;
  lobe.alpha = 0.2f;
  const Vec3f wo = direction(0.6f, 0.1f), wi = direction(0.8f, 2.0f);
  EXPECT_EQ(lobe.eval(wo, wi), lobe.eval(wo, wi));
  EXPECT_EQ(lobe.pdf(wo, wi), lobe.pdf(wo, wi));
  BsdfSample a, b;
  ASSERT_EQ(lobe.sample(wo, 0.7f, {0.2f, 0.9f}, a), lobe.sample(wo, 0.7f, {0.2f, 0.9f}, b));
  EXPECT_EQ(a.wi, b.wi);
  EXPECT_EQ(a.weight, b.weight);
  EXPECT_GT(lobe.pdf(wo, wi), 0.0f);
  EXPECT_EQ(lobe.eval(wo, -wi), Vec3f(0));
}

}  // namespace
}  // namespace ferry
