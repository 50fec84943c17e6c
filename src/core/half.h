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
    return static_cast<half>(
        sign | (absBits > 0x7f800000u ? 0x7e00u | ((absBits & 0x007fffffu) >> 13) : 0x7bffu));
  }
  if (absBits >= 0x477ff000u) return static_cast<half>(sign | 0x7bffu);  // >= 65520: saturate
  if (absBits < 0x38800000u) {                                           // subnormal or zero
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
// Four lanes, or eight (two triples at once).
[[gnu::always_inline]] inline __m256 saturateForHalf(__m256 v) {
  const __m256 signMask = _mm256_set1_ps(-0.0f);
  const __m256 big = _mm256_cmp_ps(_mm256_andnot_ps(signMask, v), _mm256_set1_ps(65504.0f),
                                   _CMP_GT_OQ);  // false for NaN
  const __m256 saturated = _mm256_or_ps(_mm256_and_ps(v, signMask), _mm256_set1_ps(65504.0f));
  return _mm256_blendv_ps(v, saturated, big);
}
[[gnu::always_inline]] inline __m128 saturateForHalf(__m128 v) {
  return _mm256_castps256_ps128(saturateForHalf(_mm256_castps128_ps256(v)));
}

// Lanes 0..2 of v.
[[gnu::always_inline]] inline void firstThreeLanes(__m128 v, float out[3]) {
  out[0] = _mm_cvtss_f32(v);
  out[1] = _mm_cvtss_f32(_mm_shuffle_ps(v, v, 1));
  out[2] = _mm_cvtss_f32(_mm_movehl_ps(v, v));
}

[[gnu::always_inline]] inline half floatToHalf(float value) {
  return static_cast<half>(_mm_extract_epi16(
      _mm_cvtps_ph(saturateForHalf(_mm_set_ss(value)), _MM_FROUND_TO_NEAREST_INT), 0));
}
[[gnu::always_inline]] inline float halfToFloat(half h) {
  return _cvtsh_ss(h);
}

// Three halves at once (a direction or a throughput), one instruction each way.
[[gnu::always_inline]] inline void floatsToHalves3(float x, float y, float z, half out[3]) {
  __m128i h = _mm_cvtps_ph(saturateForHalf(_mm_set_ps(0, z, y, x)), _MM_FROUND_TO_NEAREST_INT);
  uint64_t bits = uint64_t(_mm_cvtsi128_si64(h));
  std::memcpy(out, &bits, 6);
}
// Two triples (a direction and a throughput, adjacent in a path) in one
// conversion and two stores; returns the first triple as the halves read back
// (without reading memory just written).
[[gnu::always_inline]] inline void floatsToHalves6(const float a[3], const float b[3], half out[6],
                                                   float aQuantized[3]) {
  const __m256 v = saturateForHalf(_mm256_setr_ps(a[0], a[1], a[2], b[0], b[1], b[2], 0, 0));
  __m128i h = _mm256_cvtps_ph(v, _MM_FROUND_TO_NEAREST_INT);
  const uint64_t low = uint64_t(_mm_cvtsi128_si64(h));
  const uint32_t high = uint32_t(_mm_extract_epi32(h, 2));
  std::memcpy(out, &low, 8);
  std::memcpy(out + 4, &high, 4);
  firstThreeLanes(_mm_cvtph_ps(h), aQuantized);
}

// `packed` holds three halves in its low 48 bits (the top 16 are ignored):
// callers load them with the two bytes after them in one 8-byte load, which
// the processor forwards from earlier stores (a 6-byte copy into a zeroed
// word is three stores and one wider load, which it cannot forward).
[[gnu::always_inline]] inline void halves3ToFloats(uint64_t packed, float out[3]) {
  firstThreeLanes(_mm_cvtph_ps(_mm_cvtsi64_si128(int64_t(packed))), out);
}
#else
constexpr bool kHardwareHalf = false;

[[gnu::always_inline]] inline void floatsToHalves6(const float a[3], const float b[3], half out[6],
                                                   float aQuantized[3]) {
  for (int k = 0; k < 3; ++k) {
    out[k] = floatToHalfSoftware(a[k]);
    out[3 + k] = floatToHalfSoftware(b[k]);
    aQuantized[k] = halfToFloatSoftware(out[k]);
  }
}

[[gnu::always_inline]] inline half floatToHalf(float value) {
  return floatToHalfSoftware(value);
}
[[gnu::always_inline]] inline float halfToFloat(half h) {
  return halfToFloatSoftware(h);
}
[[gnu::always_inline]] inline void floatsToHalves3(float x, float y, float z, half out[3]) {
  out[0] = floatToHalfSoftware(x);
  out[1] = floatToHalfSoftware(y);
  out[2] = floatToHalfSoftware(z);
}
[[gnu::always_inline]] inline void halves3ToFloats(uint64_t packed, float out[3]) {
  out[0] = halfToFloatSoftware(half(packed));
  out[1] = halfToFloatSoftware(half(packed >> 16));
  out[2] = halfToFloatSoftware(half(packed >> 32));
}
#endif

inline float quantizeToHalf(float v) {
  return halfToFloat(floatToHalf(v));
}

}  // namespace ferry
