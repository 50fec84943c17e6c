// Motion: pbrt's interpolation between a start and an end transform, its
// swept bounds, and the time a ray is.
#include "scene/motion.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ferry {
namespace {

void expectNear(const Affine3f& a, const Affine3f& b, float tolerance = 1e-5f) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a.l[r][c], b.l[r][c], tolerance) << r << "," << c;
    EXPECT_NEAR(a.t[r], b.t[r], tolerance) << "t" << r;
  }
}

Affine3f turned(float degrees) {
  return Affine3f::translate({1, 2, 3}) * Affine3f::rotate({0, 0, 1}, degrees * kPi / 180) *
         Affine3f::scale({2, 1, 1});
}

TEST(InstanceMotion, ItStartsAndEndsAtItsTransforms) {
  const Affine3f sheared = [] {
    Affine3f a = turned(30);
    a.l[0][1] += 0.7f;  // a shear: more keys
    return a;
  }();
  for (const auto& [start, end] :
       {std::pair{turned(0), turned(120)}, std::pair{turned(10), sheared}}) {
    for (Vec3f pivot : {Vec3f(0), Vec3f(3, -1, 7)}) {
      const InstanceMotion m(start, end, pivot);
      expectNear(m.at(0), start);
      expectNear(m.at(1), end);
      expectNear(m.at(-1), start);  // clamped
      expectNear(m.at(2), end);
    }
  }
  EXPECT_EQ(InstanceMotion(turned(0), turned(120)).keys().size(), 2u);
  EXPECT_GT(InstanceMotion(turned(10), sheared).keys().size(), 2u);
}

TEST(InstanceMotion, RotationIsSlerpedAndScaleAndTranslationLerped) {
  // pbrt's interpolation: T, R and S apart; halfway through a 120-degree
  // turn and a stretch from 1 to 3 along x is a 60-degree turn and 2.
  const Affine3f start = Affine3f::translate({0, 0, 0});
  const Affine3f end = Affine3f::translate({4, 0, 0}) * Affine3f::rotate({0, 0, 1}, 2 * kPi / 3) *
                       Affine3f::scale({3, 1, 1});
  const InstanceMotion m(start, end);
  expectNear(m.at(0.5f), Affine3f::translate({2, 0, 0}) * Affine3f::rotate({0, 0, 1}, kPi / 3) *
                             Affine3f::scale({2, 1, 1}));
  // About a pivot (pbrt-v4's camera-centred instances): the rotation turns
  // about it, so the point at the pivot moves in a straight line.
  const Vec3f pivot(0, 5, 0);
  const InstanceMotion about(start, end, pivot);
  const Vec3f a = end.transformPoint(pivot);
  EXPECT_NEAR(length(about.at(0.5f).transformPoint(pivot) - (pivot + a) * 0.5f), 0, 1e-5f);
  EXPECT_GT(length(m.at(0.5f).transformPoint(pivot) - (pivot + a) * 0.5f), 1.0f);
}

// pbrt-v3's motion inside ObjectBegin: the part's motion, then the
// instance's. A still instance that turns and scales evenly keeps two keys
// and is exact; otherwise the product is sampled, exact at the samples and
// close between them.
TEST(InstanceMotion, APartMovingInsideAnInstanceMovesByBoth) {
  const Affine3f partStart = turned(0), partEnd = turned(90);
  const InstanceMotion part(partStart, partEnd);
  const Affine3f similar = Affine3f::translate({-2, 1, 0}) * Affine3f::rotate({0, 1, 0}, 0.5f) *
                           Affine3f::scale({1.5f, 1.5f, 1.5f});
  const InstanceMotion still = InstanceMotion::nested(similar, similar, partStart, partEnd);
  EXPECT_EQ(still.keys().size(), 2u);
  for (float u : {0.0f, 0.3f, 0.5f, 1.0f}) expectNear(still.at(u), similar * part.at(u), 1e-4f);
  const Affine3f uneven = Affine3f::scale({0.8f, 1.4f, 1});
  const InstanceMotion stretched = InstanceMotion::nested(uneven, uneven, partStart, partEnd);
  EXPECT_GT(stretched.keys().size(), 2u);
  const Affine3f outerEnd = Affine3f::translate({0, -0.8f, 0}) * Affine3f::rotate({0, 0, 1}, -0.8f);
  const InstanceMotion outer(Affine3f::identity(), outerEnd);
  const InstanceMotion both =
      InstanceMotion::nested(Affine3f::identity(), outerEnd, partStart, partEnd);
  for (float u : {0.0f, 0.25f, 0.5f, 1.0f}) {  // samples: exact
    expectNear(stretched.at(u), uneven * part.at(u), 1e-4f);
    expectNear(both.at(u), outer.at(u) * part.at(u), 1e-4f);
  }
  for (float u : {0.03f, 0.47f, 0.91f}) {  // between samples: within 0.2 % of the scale
    expectNear(stretched.at(u), uneven * part.at(u), 5e-3f);
    expectNear(both.at(u), outer.at(u) * part.at(u), 5e-3f);
  }
  // pbrt-v4's: the instance turns about a pivot (the camera), the part as before.
  const Vec3f camera(0.5f, 1, 8);
  const InstanceMotion outerAbout(Affine3f::identity(), outerEnd, camera);
  const InstanceMotion bothAbout =
      InstanceMotion::nested(Affine3f::identity(), outerEnd, partStart, partEnd, camera);
  for (float u : {0.0f, 0.25f, 0.5f, 1.0f})
    expectNear(bothAbout.at(u), outerAbout.at(u) * part.at(u), 1e-3f);
  for (float u : {0.03f, 0.47f, 0.91f})
    expectNear(bothAbout.at(u), outerAbout.at(u) * part.at(u), 2e-2f);
  // (About the origin it is another motion: the pivot is not ignored.)
  float apart = 0;
  for (int i = 0; i < 3; ++i)
    apart = std::max(apart, std::abs(bothAbout.at(0.5f).t[i] - both.at(0.5f).t[i]));
  EXPECT_GT(apart, 0.05f);
}

TEST(InstanceMotion, TheSweptBoxHoldsEveryPoseAndLittleMore) {
  const Box3f box{{-1, -0.5f, -0.2f}, {1, 0.5f, 0.2f}};
  Affine3f sheared = turned(200);
  sheared.l[1][2] += 0.5f;
  for (const auto& [start, end] :
       {std::pair{turned(0), turned(170)}, std::pair{turned(0), sheared},
        std::pair{Affine3f::identity(), Affine3f::translate({5, 0, 0})}}) {
    const InstanceMotion m(start, end, Vec3f(1, 1, 1));
    const Box3f swept = m.sweptBox(box);
    Box3f poses;
    for (int k = 0; k <= 2000; ++k) {
      const Box3f b = m.at(float(k) / 2000).transformBox(box);
      EXPECT_TRUE(swept.contains(b)) << k;
      poses.extend(b);
    }
    const float little = 0.02f * length(poses.size());
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(poses.lower[a] - swept.lower[a], little) << a;
      EXPECT_LE(swept.upper[a] - poses.upper[a], little) << a;
    }
  }
}

TEST(MotionClock, TimesAreInTheShutterAndClampedToTheMotion) {
  MotionClock clock;
  clock.shutterOpen = 0.2f, clock.shutterClose = 1.1f;
  clock.motionStart = 0, clock.motionEnd = 0.9f;
  clock.imageWidth = clock.filmWidth = 16;
  int atEnd = 0;
  double sum = 0;
  for (uint32_t pixel = 0; pixel < 256; ++pixel) {
    for (uint32_t sample = 0; sample < 16; ++sample) {
      const float u = clock.u(pixel, sample);
      EXPECT_GE(u, 0.2f / 0.9f - 1e-6f);
      EXPECT_LE(u, 1.0f);
      EXPECT_EQ(u, clock.u(pixel, sample));  // a pure function of the path
      atEnd += u == 1.0f;
      sum += u;
    }
  }
  EXPECT_NEAR(atEnd / 4096.0, 0.2 / 0.9, 0.03);  // the shutter open after the motion ends
  EXPECT_GT(sum / 4096, 0.5);
  MotionClock still;
  still.shutterOpen = still.shutterClose = 0.5f;
  still.motionStart = still.motionEnd = 0.5f;
  EXPECT_EQ(still.u(3, 1), 0.0f);  // pbrt: at or before the start time, the start transform
}

}  // namespace
}  // namespace ferry
