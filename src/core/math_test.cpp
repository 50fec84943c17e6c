#include "core/math.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace ferry {

TEST(Affine, InverseUndoesTransform) {
  Affine3f a = Affine3f::translate({1, 2, 3}) * Affine3f::rotate({0.3f, 1, 0.2f}, 0.7f) *
               Affine3f::scale({2, 0.5f, 3});
  Affine3f b = a.inverse() * a;
  Vec3f p{0.3f, -4, 7};
  Vec3f q = b.transformPoint(p);
  EXPECT_NEAR(q.x, p.x, 1e-4f);
  EXPECT_NEAR(q.y, p.y, 1e-4f);
  EXPECT_NEAR(q.z, p.z, 1e-4f);
}

TEST(Affine, NormalsStayPerpendicularUnderNonUniformScale) {
  Affine3f a = Affine3f::rotate({1, 0, 0}, 0.4f) * Affine3f::scale({1, 5, 0.2f});
  Vec3f tangent{1, 1, 0}, normal{1, -1, 0};
  EXPECT_NEAR(dot(a.transformVector(tangent), a.transformNormal(normal)), 0, 1e-5f);
}

TEST(Box, TransformedBoxContainsTransformedCorners) {
  Box3f b;
  b.extend({-1, 0, 2});
  b.extend({3, 1, 4});
  Affine3f a = Affine3f::rotate({0, 1, 0}, 1.1f) * Affine3f::translate({5, 0, 0});
  Box3f t = a.transformBox(b);
  Box3f corner;
  corner.extend(a.transformPoint({3, 1, 4}));
  EXPECT_TRUE(t.contains(corner));
}

TEST(Frame, IsOrthonormal) {
  for (Vec3f n : {Vec3f(0, 0, 1), Vec3f(0, 0, -1), normalize(Vec3f(1, 2, 3)),
                  normalize(Vec3f(-1, 0.001f, -1))}) {
    Frame f(n);
    EXPECT_NEAR(dot(f.s, f.t), 0, 1e-5f);
    EXPECT_NEAR(dot(f.s, f.n), 0, 1e-5f);
    EXPECT_NEAR(length(f.s), 1, 1e-5f);
    Vec3f v = normalize(Vec3f(0.2f, -0.7f, 0.4f));
    Vec3f back = f.toWorld(f.toLocal(v));
    EXPECT_NEAR(back.x, v.x, 1e-5f);
  }
}

TEST(Math, SinCosTwoPiIsWithinTwoTenMillionthsOfTheTrueValues) {
  double worst = 0;
  auto check = [&](float u) {
    float s, c;
    sinCosTwoPi(u, s, c);
    const double angle = 2 * 3.14159265358979323846 * double(u);
    worst = std::max({worst, std::abs(s - std::sin(angle)), std::abs(c - std::cos(angle))});
  };
  for (uint32_t i = 0; i <= (1u << 24); ++i) check(float(i) * 0x1p-24f);  // every sampler input
  check(1.0f);
  EXPECT_LT(worst, 2e-7);
  float s, c;
  sinCosTwoPi(0.25f, s, c);
  EXPECT_EQ(s, 1.0f);
  EXPECT_EQ(c, 0.0f);
  sinCosTwoPi(0.5f, s, c);
  EXPECT_EQ(c, -1.0f);
}

}  // namespace ferry
