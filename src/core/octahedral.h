// Unit vectors in 32 bits (octahedral mapping, Meyer et al. 2010; Cigolle et
// al. 2014, "A Survey of Efficient Representations for Independent Unit
// Vectors") and positive densities in 16 bits: what the compact path stores.
//
// A decoded direction is at most ~7e-5 rad off (tested). Encoding and
// decoding are plain float arithmetic (built with -ffp-contract=off), so
// every rank decodes exactly the same ray. Why 32 bits: docs/data-parallel.md,
// "The path on the wire".
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/math.h"

namespace ferry {

namespace octahedral_detail {
constexpr float kScale = 32767.0f;
[[gnu::always_inline]] inline uint32_t quantize(float v) {
  // [-1, 1] -> [-32767, 32767] rounded to nearest; NaN goes to -1.
  v = v > -1.0f ? (v < 1.0f ? v : 1.0f) : -1.0f;
  return uint32_t(uint16_t(int16_t(std::floor(v * kScale + 0.5f))));
}
}  // namespace octahedral_detail

// Any non-zero vector (need not be unit); zero and non-finite vectors encode
// to some valid direction.
[[gnu::always_inline]] inline uint32_t encodeOctahedral(Vec3f d) {
  const float l1 = std::abs(d.x) + std::abs(d.y) + std::abs(d.z);
  if (!(l1 > 0) || !std::isfinite(l1)) return 0;  // decodes to +z
  float x = d.x / l1, y = d.y / l1;
  if (d.z < 0) {  // the lower half folds over the diagonals
    const float ox = x;
    x = std::copysign(1 - std::abs(y), ox);
    y = std::copysign(1 - std::abs(ox), y);
  }
  return octahedral_detail::quantize(x) | (octahedral_detail::quantize(y) << 16);
}

// The unit vector an encoding stands for.
[[gnu::always_inline]] inline Vec3f decodeOctahedral(uint32_t packed) {
  constexpr float kInv = 1.0f / octahedral_detail::kScale;
  float x = float(int16_t(uint16_t(packed))) * kInv;
  float y = float(int16_t(uint16_t(packed >> 16))) * kInv;
  const float z = 1 - std::abs(x) - std::abs(y);
  if (z < 0) {
    const float ox = x;
    x = std::copysign(1 - std::abs(y), ox);
    y = std::copysign(1 - std::abs(ox), y);
  }
  const float inv = 1 / std::sqrt(x * x + y * y + z * z);
  return {x * inv, y * inv, z * inv};
}

// A density (>= 0, may be infinite) as the top 16 bits of its float, rounded
// to nearest even: 8 exponent bits keep any density a BSDF produces, 7
// mantissa bits keep it to 0.4%, which is all a MIS weight needs (both of the
// weights that must sum to one are computed from the stored value). NaN and
// negative values store 0.
[[gnu::always_inline]] inline uint16_t packDensity(float pdf) {
  if (!(pdf > 0)) return 0;
  uint32_t bits;
  std::memcpy(&bits, &pdf, 4);
  if (bits >= 0x7f800000u) return 0x7f80;  // infinity
  bits += 0x7fffu + ((bits >> 16) & 1u);   // carries into the exponent as it should
  return uint16_t(std::min(bits >> 16, 0x7f80u));
}
[[gnu::always_inline]] inline float unpackDensity(uint16_t packed) {
  const uint32_t bits = uint32_t(packed) << 16;
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

}  // namespace ferry
