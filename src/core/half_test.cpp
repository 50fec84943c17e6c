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
    bits = sign | 0x7f800000u | (mantissa << 13) |
           (mantissa ? 0x00400000u : 0);  // NaNs come out quiet
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
    float fast = halfToFloatSoftware(half(h)), reference = referenceHalfToFloat(half(h));
    uint32_t a, b;
    std::memcpy(&a, &fast, 4);
    std::memcpy(&b, &reference, 4);
    ASSERT_EQ(a, b) << "half 0x" << std::hex << h;
  }
}

uint32_t bitsOf(float f) {
  uint32_t b;
  std::memcpy(&b, &f, 4);
  return b;
}
float floatOf(uint32_t b) {
  float f;
  std::memcpy(&f, &b, 4);
  return f;
}

// Where the build uses F16C, the instruction must give the software's bits.
TEST(Half, HardwareHalfToFloatEqualsSoftwareForEveryHalf) {
  if (!kHardwareHalf) GTEST_SKIP() << "software conversion only in this build";
  for (uint32_t h = 0; h < 0x10000; ++h) {
    ASSERT_EQ(bitsOf(halfToFloat(half(h))), bitsOf(halfToFloatSoftware(half(h))))
        << "half 0x" << std::hex << h;
    half three[3] = {half(h), half(h ^ 0x8000u), half(h ^ 0x0155u)};
    float out[3];
    halves3ToFloats(uint64_t(three[0]) | uint64_t(three[1]) << 16 | uint64_t(three[2]) << 32 |
                        uint64_t(0xabcd) << 48,
                    out);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(bitsOf(out[k]), bitsOf(halfToFloatSoftware(three[k])));
  }
}

// The rounding of float -> half depends on the low 13 mantissa bits only
// through their relation to the halfway point, so every sign, exponent and top
// mantissa (2^19 prefixes) with the low bits that matter covers every case.
// (All 2^32 floats were also compared once, when this was written.)
TEST(Half, HardwareFloatToHalfEqualsSoftwareOnEveryRoundingCase) {
  if (!kHardwareHalf) GTEST_SKIP() << "software conversion only in this build";
  const uint32_t lows[] = {0,      1,      2,      0x7ff,  0xfff,  0x1000,
                           0x1001, 0x17ff, 0x1fff, 0x0800, 0x1800, 0x0abc};
  for (uint32_t prefix = 0; prefix < (1u << 19); ++prefix) {
    for (uint32_t low : lows) {
      const float f = floatOf((prefix << 13) | low);
      const half expected = floatToHalfSoftware(f);
      ASSERT_EQ(floatToHalf(f), expected) << "float bits 0x" << std::hex << bitsOf(f);
      half three[3];
      floatsToHalves3(f, -f, 0.5f, three);
      const float a[3] = {0.25f, f, -f}, b[3] = {f, 1e9f, -0.0f};
      half six[6];
      float back[3];
      floatsToHalves6(a, b, six, back);
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(six[k], floatToHalfSoftware(a[k]));
        ASSERT_EQ(six[3 + k], floatToHalfSoftware(b[k]));
        ASSERT_EQ(bitsOf(back[k]), bitsOf(halfToFloatSoftware(six[k])));
      }
      ASSERT_EQ(three[0], expected);
      ASSERT_EQ(three[1], floatToHalfSoftware(-f));
      ASSERT_EQ(three[2], floatToHalfSoftware(0.5f));
    }
  }
}

// For a one-off check of every float: --gtest_also_run_disabled_tests.
TEST(Half, DISABLED_HardwareFloatToHalfEqualsSoftwareForEveryFloat) {
  if (!kHardwareHalf) GTEST_SKIP() << "software conversion only in this build";
  for (uint64_t b = 0; b < (uint64_t(1) << 32); ++b) {
    const float f = floatOf(uint32_t(b));
    ASSERT_EQ(floatToHalf(f), floatToHalfSoftware(f)) << "float bits 0x" << std::hex << b;
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
