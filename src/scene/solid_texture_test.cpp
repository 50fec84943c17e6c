#include "scene/solid_texture.h"

#include <gtest/gtest.h>

#include <cmath>

#include "scene/texture.h"

namespace ferry {
namespace {

TEST(SolidTexture, NoiseIsZeroOnTheLatticeBoundedAndContinuous) {
  for (int x = -3; x <= 3; ++x)
    for (int y = -3; y <= 3; ++y)
      for (int z = -3; z <= 3; ++z) EXPECT_EQ(perlinNoise(Vec3f(float(x), float(y), float(z))), 0);
  double sum = 0;
  float largest = 0;
  constexpr int kSteps = 200000;
  for (int i = 0; i < kSteps; ++i) {
    const Vec3f p{0.0137f * float(i), 7.3f - 0.0071f * float(i), 0.0029f * float(i) - 40};
    const float n = perlinNoise(p);
    largest = std::max(largest, std::abs(n));
    sum += n;
    // Continuous: a tiny step moves it a little (its gradient is at most ~3).
    EXPECT_LE(std::abs(perlinNoise(p + Vec3f(1e-3f, 0, 0)) - n), 4e-3f) << i;
  }
  EXPECT_LE(largest, 1.1f);
  EXPECT_GT(largest, 0.5f);
  EXPECT_NEAR(sum / kSteps, 0, 0.02);
}

TEST(SolidTexture, FbmAndTurbulenceSumOctavesAsPbrt) {
  const Vec3f p{0.3f, 1.7f, -2.2f};
  float expected = 0, lambda = 1, o = 1, expectedTurbulence = 0;
  for (int i = 0; i < 5; ++i) {
    expected += o * perlinNoise(p * lambda);
    expectedTurbulence += o * std::abs(perlinNoise(p * lambda));
    lambda *= 1.99f;
    o *= 0.6f;
  }
  EXPECT_FLOAT_EQ(fractalBrownianMotion(p, 0.6f, 5), expected);
  EXPECT_FLOAT_EQ(turbulence(p, 0.6f, 5), expectedTurbulence + o * 0.2f);
}

TEST(SolidTexture, MarbleFollowsPbrtV3sSpline) {
  SolidTexture marble;
  marble.kind = SolidTextureKind::Marble;
  marble.variation = 0;  // no veins: the colour is the spline at 0.5 + 0.5 sin(y)
  // sin(y) = -1: t = 0, the first control point times 1.5.
  const Vec3f low = marble.evaluate({0.2f, -kPi / 2, 5});
  EXPECT_NEAR(low.x, 1.5f * 0.58f, 1e-5f);
  EXPECT_NEAR(low.z, 1.5f * 0.6f, 1e-5f);
  // sin(y) = 1: t = 1, the end of the last segment: the last control point.
  const Vec3f high = marble.evaluate({0, kPi / 2, 0});
  EXPECT_NEAR(high.x, 1.5f * 0.58f, 1e-5f);
  EXPECT_NEAR(high.z, 1.5f * 0.6f, 1e-5f);
  // Never extrapolated: every colour between the control points' range.
  for (int i = 0; i <= 1000; ++i) {
    const Vec3f c = marble.evaluate({0, kPi * (float(i) / 1000 - 0.5f), 0});
    ASSERT_GE(c.z, 1.5f * 0.2f) << i;
    ASSERT_LE(c.x, 1.5f * 0.6f) << i;
  }
  // Scale multiplies the texture space; the transform places it.
  marble.scale = 2;
  marble.worldToTexture = Affine3f::translate({0, 1, 0});
  EXPECT_NEAR(marble.evaluate({0, -kPi / 4 - 1, 0}).x, 1.5f * 0.58f, 1e-5f);
  // Veins vary the colour along x too.
  marble.variation = 0.5f;
  const Vec3f a = marble.evaluate({0.1f, 0.3f, 0.2f}), b = marble.evaluate({2.7f, 0.3f, 0.2f});
  EXPECT_NE(a.x, b.x);
}

TEST(SolidTexture, AnImageTextureIgnoresThePointAndASolidOneTheUv) {
  Texture solid;
  solid.solid.kind = SolidTextureKind::Fbm;
  EXPECT_EQ(solid.evaluate({0.1f, 0.1f}, {0.4f, 0.5f, 0.6f}).x,
            solid.evaluate({0.9f, 0.3f}, {0.4f, 0.5f, 0.6f}).x);
  EXPECT_NE(solid.evaluate({0.1f, 0.1f}, {0.4f, 0.5f, 0.6f}).x,
            solid.evaluate({0.1f, 0.1f}, {1.4f, 0.5f, 0.6f}).x);
  Texture image;  // no texels: white
  EXPECT_EQ(image.evaluate({0.2f, 0.3f}, {1, 2, 3}).x, 1);
}

// A combination evaluates its operands at the point: constants, solid parts
// and image parts, as pbrt's scale, mix, checkerboard, dots and bilerp.
TEST(SolidTexture, CombinationsEvaluateTheirOperandsAtThePoint) {
  Texture fbm;
  fbm.solid.kind = SolidTextureKind::Fbm;
  Texture image;  // 2x1: red on the left, blue on the right, linear
  image.width = 2;
  image.height = 1;
  image.srgb = false;
  image.wrap = WrapMode::Clamp;
  image.rgba = {255, 0, 0, 255, 0, 0, 255, 255};
  auto combined = [&](TextureCombination kind) {
    Texture t;
    t.combination = kind;
    t.parts = {fbm, image};
    t.operands[0].part = 0;
    t.operands[1].part = 1;
    t.operands[2].constant = Vec3f(0.25f);
    t.operands[3].constant = Vec3f(2);
    return t;
  };
  const Vec3f p{0.3f, 1.7f, 2.2f}, q{4.1f, 0.2f, 0.9f};
  const float n = fbm.solid.evaluate(p).x;
  const Vec2f left{0.1f, 0.5f}, right{0.9f, 0.5f};
  EXPECT_TRUE(combined(TextureCombination::None).isSolid() == false);
  const Texture scale = combined(TextureCombination::Scale);
  EXPECT_TRUE(scale.isSolid());
  EXPECT_EQ(scale.value(left, p), Vec3f(n, 0, 0));
  EXPECT_EQ(scale.value(right, p), Vec3f(0, 0, n));
  EXPECT_NE(scale.value(left, p).x, scale.value(left, q).x);
  const Texture mix = combined(TextureCombination::Mix);  // by the constant 0.25
  EXPECT_NEAR(mix.value(left, p).x, 0.75f * n + 0.25f, 1e-6f);
  EXPECT_NEAR(mix.value(left, p).z, 0.75f * n, 1e-6f);
  Texture checker = combined(TextureCombination::Checkerboard);
  checker.mapping = {2, 2, 0, 0};
  EXPECT_EQ(checker.value({0.25f, 0.25f}, p), Vec3f(n));        // square (0, 0): even
  EXPECT_EQ(checker.value({0.75f, 0.25f}, p), Vec3f(0, 0, 1));  // (1, 0): odd, the image
  const Texture dots = combined(TextureCombination::Dots);
  int inside = 0;
  for (int i = 0; i < 400; ++i) {
    const Vec2f uv{float(i % 20) / 20 + 0.025f, float(i / 20) / 20 + 0.025f};
    const bool in = insideDot(uv);
    inside += in;
    EXPECT_EQ(dots.value(uv, p), in ? Vec3f(n) : image.value(uv, p));
  }
  EXPECT_GT(inside, 0);
  EXPECT_LT(inside, 400);
  const Texture bilerp =
      combined(TextureCombination::Bilerp);  // v00 fbm, v01 image, v10 0.25, v11 2
  const Vec2f middle{0.5f, 0.5f};
  EXPECT_NEAR(bilerp.value(middle, p).x, 0.25f * (n + image.value(middle, p).x + 0.25f + 2), 1e-6f);
  // A colour clamps the negative values a raw value keeps.
  const Vec3f negative{-0.5f, 0.5f, 0};
  Texture shifted;
  shifted.combination = TextureCombination::Scale;
  shifted.operands[0].constant = negative;
  EXPECT_EQ(shifted.value(left, p), negative);
  const Vec4f colour = shifted.evaluate(left, p);
  EXPECT_EQ(colour.xyz(), Vec3f(0, 0.5f, 0));
  EXPECT_EQ(colour.w, 1.0f);
}

}  // namespace
}  // namespace ferry
