// IEEE 754 half-precision conversion, in software so that every machine
// quantizes exactly the same way (the compact path stores directions and
// throughput as halves, and one-rank and many-rank renders must trace
// bit-identical rays).
#pragma once

#include <cstdint>
#include <cstring>

namespace ferry {

using half = uint16_t;

// Round-to-nearest-even float -> half; overflow saturates to the largest finite
// half (65504) rather than infinity, so a bright throughput stays finite.
[[gnu::always_inline]] inline half floatToHalf(float value) {
  uint32_t bits;
  std::memcpy(&bits, &value, 4);
  uint32_t sign = (bits >> 16) & 0x8000u;
  uint32_t absBits = bits & 0x7fffffffu;
  if (absBits >= 0x7f800000u) {  // inf or nan
    return static_cast<half>(sign | (absBits > 0x7f800000u ? 0x7e00u : 0x7bffu));
  }
  if (absBits >= 0x477ff000u) return static_cast<half>(sign | 0x7bffu);  // >= 65520: saturate
  if (absBits < 0x38800000u) {                                          // subnormal or zero
    if (absBits < 0x33000000u) return static_cast<half>(sign);
    uint32_t mantissa = (absBits & 0x007fffffu) | 0x00800000u;
    int shift = 113 - static_cast<int>(absBits >> 23);
    uint32_t halfMant = mantissa >> (shift + 13);
    uint32_t rest = mantissa & ((1u << (shift + 13)) - 1);
    uint32_t halfway = 1u << (shift + 12);
    if (rest > halfway || (rest == halfway && (halfMant & 1u))) ++halfMant;
    return static_cast<half>(sign | halfMant);
  }
  uint32_t rebased = absBits - 0x38000000u;  // exponent 127 -> 15
  uint32_t h = rebased >> 13;
  uint32_t rest = rebased & 0x1fffu;
  if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;
  if (h >= 0x7c00u) h = 0x7bffu;
  return static_cast<half>(sign | h);
}

// Exact for every half (normals, subnormals, infinities, NaNs) and branch-light:
// the exponent is rebased by an integer add, subnormals are renormalized by one
// exact float subtraction. (The bit-by-bit reference is in half_test.cpp, which
// checks all 65,536 values against it.)
[[gnu::always_inline]] inline float halfToFloat(half h) {
  uint32_t bits = (static_cast<uint32_t>(h) & 0x7fffu) << 13;  // exponent and mantissa
  const uint32_t exponent = bits & 0x0f800000u;
  bits += (127 - 15) << 23;
  float f;
  if (exponent == 0x0f800000u) {  // inf or nan
    bits += (128 - 16) << 23;
    std::memcpy(&f, &bits, 4);
  } else if (exponent == 0) {  // zero or subnormal: (1 + m / 1024) 2^-14 - 2^-14 = m 2^-24
    bits += 1u << 23;
    std::memcpy(&f, &bits, 4);
    f -= 0x1p-14f;
  } else {
    std::memcpy(&f, &bits, 4);
  }
  uint32_t out;
  std::memcpy(&out, &f, 4);
  out |= (static_cast<uint32_t>(h) & 0x8000u) << 16;
  std::memcpy(&f, &out, 4);
  return f;
}

inline float quantizeToHalf(float v) { return halfToFloat(floatToHalf(v)); }

}  // namespace ferry
