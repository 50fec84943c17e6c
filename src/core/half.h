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
inline half floatToHalf(float value) {
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

inline float halfToFloat(half h) {
  uint32_t sign = (static_cast<uint32_t>(h) & 0x8000u) << 16;
  uint32_t exponent = (h >> 10) & 0x1fu;
  uint32_t mantissa = h & 0x3ffu;
  uint32_t bits;
  if (exponent == 0) {
    if (mantissa == 0) {
      bits = sign;
    } else {  // subnormal: normalize
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

inline float quantizeToHalf(float v) { return halfToFloat(floatToHalf(v)); }

}  // namespace ferry
