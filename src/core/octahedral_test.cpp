#include "core/octahedral.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/random.h"

namespace ferry {
namespace {

float angleBetween(Vec3f a, Vec3f b) {
  // atan2 of |a x b| and a . b: accurate for tiny angles (acos is not).
  return std::atan2(length(cross(a, b)), dot(a, b));
}

TEST(Octahedral, RoundTripsEveryDirectionWithin7e5Radians) {
  float worst = 0;
  for (uint32_t i = 0; i < 2000000; ++i) {
    const float z = 1 - 2 * (float(i) + 0.5f) / 2000000;
    const float phi = float(i) * 2.39996323f;  // golden angle: a Fibonacci sphere
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    const Vec3f d{r * std::cos(phi), r * std::sin(phi), z};
    const Vec3f back = decodeOctahedral(encodeOctahedral(d));
    ASSERT_NEAR(length(back), 1.0f, 1e-6f);
    worst = std::max(worst, angleBetween(normalize(d), back));
  }
  EXPECT_LT(worst, 7e-5f);
}

TEST(Octahedral, AxesAndDiagonalsAreExactAndScaleDoesNotMatter) {
  const Vec3f axes[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (Vec3f a : axes) {
    const Vec3f back = decodeOctahedral(encodeOctahedral(a));
    EXPECT_EQ(back.x, a.x);
    EXPECT_EQ(back.y, a.y);
    EXPECT_EQ(back.z, a.z);
    EXPECT_EQ(encodeOctahedral(a * 1e-20f), encodeOctahedral(a));
    EXPECT_EQ(encodeOctahedral(a * 1e20f), encodeOctahedral(a));
  }
}

TEST(Octahedral, DecodingIsAFunctionOfTheBitsAndStableUnderReEncoding) {
  // What a rank decodes and re-encodes (a forwarded ray is sent as stored)
  // must be the same ray.
  for (uint32_t bits = 0; bits < (1u << 22); bits += 97) {
    const uint32_t packed = bits * 2654435761u;
    const Vec3f d = decodeOctahedral(packed);
    ASSERT_TRUE(isFinite(d));
    const Vec3f again = decodeOctahedral(encodeOctahedral(d));
    ASSERT_LT(angleBetween(d, again), 7e-5f);
  }
}

TEST(Octahedral, DegenerateInputsEncodeToAValidDirection) {
  for (Vec3f d : {Vec3f(0, 0, 0), Vec3f(NAN, 0, 1), Vec3f(INFINITY, 1, 0)}) {
    const Vec3f back = decodeOctahedral(encodeOctahedral(d));
    EXPECT_TRUE(isFinite(back));
    EXPECT_NEAR(length(back), 1.0f, 1e-6f);
  }
}

TEST(PackedDensity, KeepsDensitiesToWithinAQuarterPercent) {
  for (float pdf = 1e-30f; pdf < 1e30f; pdf *= 1.37f) {
    const float back = unpackDensity(packDensity(pdf));
    ASSERT_NEAR(back / pdf, 1.0f, 1.0f / 256) << pdf;
  }
  EXPECT_EQ(unpackDensity(packDensity(1.0f)), 1.0f);
  EXPECT_EQ(unpackDensity(packDensity(0.25f)), 0.25f);
}

TEST(PackedDensity, ZeroNegativeNanStoreZeroAndInfinityStaysInfinite) {
  EXPECT_EQ(packDensity(0), 0);
  EXPECT_EQ(packDensity(-3), 0);
  EXPECT_EQ(packDensity(NAN), 0);
  EXPECT_TRUE(std::isinf(unpackDensity(packDensity(INFINITY))));
  EXPECT_TRUE(std::isinf(unpackDensity(packDensity(3.4e38f))));  // rounds up to infinity
}

}  // namespace
}  // namespace ferry
