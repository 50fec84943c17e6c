#include "core/half.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace ferry {
namespace {

// The bit-by-bit conversion halfToFloat replaced (and must agree with everywhere).
float referenceHalfToFloat(half h) {
  uint32_t sign = (static_cast<uint32_t>(h) & 0x8000u) << 16;
  uint32_t exponent = (h >> 10) & 0x1fu;
  uint32_t mantissa = h & 0x3ffu;
  uint32_t bits;
  if (exponent == 0) {
    if (mantissa == 0) {
      bits = sign;
    } else {
      int e = -1;
      do {
        ++e;
        mantissa <<= 1;
      } while ((mantissa & 0x400u) == 0);
      bits = sign | ((112 - e) << 23) | ((mantissa & 0x3ffu) << 13);
    }
  } else if (exponent == 31) {
    bits = sign | 0x7f800000u | (mantissa << 13);
  } else {
    bits = sign | ((exponent + 112) << 23) | (mantissa << 13);
  }
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

}  // namespace

TEST(Half, HalfToFloatIsBitIdenticalToTheReferenceForEveryHalf) {
  for (uint32_t h = 0; h < 0x10000; ++h) {
    float fast = halfToFloat(half(h)), reference = referenceHalfToFloat(half(h));
    uint32_t a, b;
    std::memcpy(&a, &fast, 4);
    std::memcpy(&b, &reference, 4);
    ASSERT_EQ(a, b) << "half 0x" << std::hex << h;
  }
}

TEST(Half, ExactValuesRoundTrip) {
  for (float v : {0.0f, 1.0f, -1.0f, 0.5f, 2.0f, 1024.0f, 65504.0f, -0.25f, 6.103515625e-05f})
    EXPECT_EQ(halfToFloat(floatToHalf(v)), v) << v;
}

TEST(Half, EveryHalfRoundTripsThroughFloat) {
  for (uint32_t h = 0; h < 0x10000; ++h) {
    if ((h & 0x7c00) == 0x7c00) continue;  // inf / nan
    float f = halfToFloat(half(h));
    EXPECT_EQ(floatToHalf(f), half(h)) << h;
  }
}

TEST(Half, RelativeErrorWithinHalfUlp) {
  for (float v = 1e-3f; v < 6e4f; v *= 1.0137f) {
    float q = quantizeToHalf(v);
    EXPECT_LE(std::abs(q - v) / v, 1.0f / 2048.0f + 1e-7f) << v;
  }
}

TEST(Half, OverflowSaturatesAndNanStaysNan) {
  EXPECT_EQ(halfToFloat(floatToHalf(1e9f)), 65504.0f);
  EXPECT_EQ(halfToFloat(floatToHalf(-1e9f)), -65504.0f);
  EXPECT_TRUE(std::isnan(halfToFloat(floatToHalf(std::nanf("")))));
}

TEST(Half, SubnormalsRoundToNearest) {
  float smallest = std::ldexp(1.0f, -24);
  EXPECT_EQ(halfToFloat(floatToHalf(smallest)), smallest);
  EXPECT_EQ(halfToFloat(floatToHalf(smallest * 0.49f)), 0.0f);
  EXPECT_EQ(halfToFloat(floatToHalf(smallest * 3)), smallest * 3);
}

}  // namespace ferry
