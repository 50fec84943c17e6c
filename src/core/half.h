// IEEE 754 half-precision conversion. The compact path stores directions and
// throughput as halves, and one-rank and many-rank renders must trace
// bit-identical rays, so every build must quantize exactly alike: the
// software conversions below define the result for every input, and where the
// build targets F16C (x86-64-v3, see CMakeLists.txt) the hardware conversion
// is used instead, set up to give the same bits (half_test.cpp checks all
// 65,536 halves and every rounding case of the floats).
#pragma once

#include <cstdint>
#include <cstring>

#if defined(__F16C__)
#include <immintrin.h>
#endif

namespace ferry {

using half = uint16_t;

// Round-to-nearest-even float -> half; overflow saturates to the largest finite
// half (65504) rather than infinity, so a bright throughput stays finite. A NaN
// stays a quiet NaN with the top of its payload (as the F16C instruction does).
[[gnu::always_inline]] inline half floatToHalfSoftware(float value) {
  uint32_t bits;
  std::memcpy(&bits, &value, 4);
  uint32_t sign = (bits >> 16) & 0x8000u;
  uint32_t absBits = bits & 0x7fffffffu;
  if (absBits >= 0x7f800000u) {  // inf or nan
    return static_cast<half>(sign | (absBits > 0x7f800000u ? 0x7e00u | ((absBits & 0x007fffffu) >> 13) : 0x7bffu));
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

// Exact for every half (normals, subnormals, infinities; a NaN comes out
// quiet, as from the F16C instruction) and branch-light: the exponent is
// rebased by an integer add, subnormals are renormalized by one exact float
// subtraction. (The bit-by-bit reference is in half_test.cpp, which checks all
// 65,536 values against it.)
[[gnu::always_inline]] inline float halfToFloatSoftware(half h) {
  uint32_t bits = (static_cast<uint32_t>(h) & 0x7fffu) << 13;  // exponent and mantissa
  const uint32_t exponent = bits & 0x0f800000u;
  bits += (127 - 15) << 23;
  float f;
  if (exponent == 0x0f800000u) {  // inf or nan
    bits += (128 - 16) << 23;
    if (bits & 0x007fffffu) bits |= 0x00400000u;  // quiet
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

#if defined(__F16C__)
constexpr bool kHardwareHalf = true;

// The saturation of floatToHalfSoftware (the instruction rounds overflow to
// infinity): |v| > 65504 becomes +-65504 (infinities too); NaN stays NaN.
[[gnu::always_inline]] inline __m128 saturateForHalf(__m128 v) {
  const __m128 signMask = _mm_set1_ps(-0.0f);
  const __m128 big = _mm_cmpgt_ps(_mm_andnot_ps(signMask, v), _mm_set1_ps(65504.0f));  // false for NaN
  const __m128 saturated = _mm_or_ps(_mm_and_ps(v, signMask), _mm_set1_ps(65504.0f));
  return _mm_blendv_ps(v, saturated, big);
}

[[gnu::always_inline]] inline half floatToHalf(float value) {
  return static_cast<half>(
      _mm_extract_epi16(_mm_cvtps_ph(saturateForHalf(_mm_set_ss(value)), _MM_FROUND_TO_NEAREST_INT), 0));
}
[[gnu::always_inline]] inline float halfToFloat(half h) { return _cvtsh_ss(h); }

// Three halves at once (a direction or a throughput), one instruction each way.
[[gnu::always_inline]] inline void floatsToHalves3(float x, float y, float z, half out[3]) {
  __m128i h = _mm_cvtps_ph(saturateForHalf(_mm_set_ps(0, z, y, x)), _MM_FROUND_TO_NEAREST_INT);
  uint64_t bits = uint64_t(_mm_cvtsi128_si64(h));
  std::memcpy(out, &bits, 6);
}
[[gnu::always_inline]] inline void halves3ToFloats(const half in[3], float out[3]) {
  uint64_t bits = 0;
  std::memcpy(&bits, in, 6);
  __m128 f = _mm_cvtph_ps(_mm_cvtsi64_si128(int64_t(bits)));
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, f);
  out[0] = lanes[0];
  out[1] = lanes[1];
  out[2] = lanes[2];
}
#else
constexpr bool kHardwareHalf = false;

[[gnu::always_inline]] inline half floatToHalf(float value) { return floatToHalfSoftware(value); }
[[gnu::always_inline]] inline float halfToFloat(half h) { return halfToFloatSoftware(h); }
[[gnu::always_inline]] inline void floatsToHalves3(float x, float y, float z, half out[3]) {
  out[0] = floatToHalfSoftware(x);
  out[1] = floatToHalfSoftware(y);
  out[2] = floatToHalfSoftware(z);
}
[[gnu::always_inline]] inline void halves3ToFloats(const half in[3], float out[3]) {
  out[0] = halfToFloatSoftware(in[0]);
  out[1] = halfToFloatSoftware(in[1]);
  out[2] = halfToFloatSoftware(in[2]);
}
#endif

inline float quantizeToHalf(float v) { return halfToFloat(floatToHalf(v)); }

}  // namespace ferry
