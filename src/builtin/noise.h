// Deterministic randomness for the procedural scenes: a counter-based number
// stream and hash-based gradient noise. Everything is a pure function of its
// keys, so a scene element can be regenerated alone (describe, parallel
// generation, per-instance placement) and always comes out the same.
#pragma once

#include <cmath>
#include <cstdint>

#include "core/math.h"
#include "core/random.h"

namespace ferry::builtin {

// Keys for independent streams: one per (seed, purpose, index...). Mixing the
// seed through its own finalizer keeps seeds 1 and 2 unrelated.
inline uint32_t streamKey(uint32_t seed, uint32_t a, uint32_t b = 0, uint32_t c = 0) {
  return hashCombine(hashCombine(hashCombine(hashMix(seed + 0x3c6ef372u), a), b), c);
}

// A stream of uniform numbers; holds only its key and a counter, so copies are
// cheap and two streams with different keys never interact.
class HashRng {
 public:
  explicit HashRng(uint32_t key) : key_(key) {}
  HashRng(uint32_t seed, uint32_t a, uint32_t b = 0, uint32_t c = 0)
      : key_(streamKey(seed, a, b, c)) {}

  uint32_t bits() { return hashCombine(key_, counter_++); }
  // [0, 1) with 24 bits, exactly representable in float.
  float uniform() { return static_cast<float>(bits() >> 8) * 0x1p-24f; }
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  // Uniform in the unit disc (polar mapping: no rejection, fixed cost).
  Vec2f inDisc() {
    float r = std::sqrt(uniform());
    float a = 2 * kPi * uniform();
    return {r * std::cos(a), r * std::sin(a)};
  }
  // Uniform direction on the unit sphere.
  Vec3f onSphere() {
    float z = 1 - 2 * uniform();
    float r = std::sqrt(std::max(0.0f, 1 - z * z));
    float a = 2 * kPi * uniform();
    return {r * std::cos(a), z, r * std::sin(a)};
  }

 private:
  uint32_t key_;
  uint32_t counter_ = 0;
};

inline float smoothstep(float edge0, float edge1, float x) {
  float t = std::clamp((x - edge0) / (edge1 - edge0), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}

inline float lerpf(float a, float b, float t) {
  return a + (b - a) * t;
}

namespace detail {

inline float fade(float t) {
  return t * t * t * (t * (t * 6 - 15) + 10);
}

inline float gradient2(uint32_t seed, int32_t ix, int32_t iy, float dx, float dy) {
  // Eight unit-ish directions: cheaper than cos/sin of a hashed angle.
  static constexpr float kGx[8] = {1, -1, 0, 0, 0.7071f, -0.7071f, 0.7071f, -0.7071f};
  static constexpr float kGy[8] = {0, 0, 1, -1, 0.7071f, 0.7071f, -0.7071f, -0.7071f};
  uint32_t h = hashCombine(hashCombine(seed, static_cast<uint32_t>(ix)), static_cast<uint32_t>(iy));
  uint32_t k = h & 7u;
  return kGx[k] * dx + kGy[k] * dy;
}

inline float gradient3(uint32_t seed, int32_t ix, int32_t iy, int32_t iz, float dx, float dy,
                       float dz) {
  // The twelve cube-edge directions of improved Perlin noise (16 with repeats).
  static constexpr float kG[16][3] = {{1, 1, 0}, {-1, 1, 0}, {1, -1, 0}, {-1, -1, 0},
                                      {1, 0, 1}, {-1, 0, 1}, {1, 0, -1}, {-1, 0, -1},
                                      {0, 1, 1}, {0, -1, 1}, {0, 1, -1}, {0, -1, -1},
                                      {1, 1, 0}, {-1, 1, 0}, {0, -1, 1}, {0, -1, -1}};
  uint32_t h = hashCombine(
      hashCombine(hashCombine(seed, static_cast<uint32_t>(ix)), static_cast<uint32_t>(iy)),
      static_cast<uint32_t>(iz));
  const float* g = kG[h & 15u];
  return g[0] * dx + g[1] * dy + g[2] * dz;
}

}  // namespace detail

// Gradient noise in roughly [-1, 1], zero at integer lattice points.
inline float gradientNoise(float x, float y, uint32_t seed) {
  float fx = std::floor(x), fy = std::floor(y);
  int32_t ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy);
  float tx = x - fx, ty = y - fy;
  float n00 = detail::gradient2(seed, ix, iy, tx, ty);
  float n10 = detail::gradient2(seed, ix + 1, iy, tx - 1, ty);
  float n01 = detail::gradient2(seed, ix, iy + 1, tx, ty - 1);
  float n11 = detail::gradient2(seed, ix + 1, iy + 1, tx - 1, ty - 1);
  float u = detail::fade(tx), v = detail::fade(ty);
  return 1.4142f * lerpf(lerpf(n00, n10, u), lerpf(n01, n11, u), v);
}

inline float gradientNoise(Vec3f p, uint32_t seed) {
  float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  int32_t ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy),
          iz = static_cast<int32_t>(fz);
  float tx = p.x - fx, ty = p.y - fy, tz = p.z - fz;
  float u = detail::fade(tx), v = detail::fade(ty), w = detail::fade(tz);
  auto g = [&](int dx, int dy, int dz) {
    return detail::gradient3(seed, ix + dx, iy + dy, iz + dz, tx - dx, ty - dy, tz - dz);
  };
  float x00 = lerpf(g(0, 0, 0), g(1, 0, 0), u), x10 = lerpf(g(0, 1, 0), g(1, 1, 0), u);
  float x01 = lerpf(g(0, 0, 1), g(1, 0, 1), u), x11 = lerpf(g(0, 1, 1), g(1, 1, 1), u);
  return lerpf(lerpf(x00, x10, v), lerpf(x01, x11, v), w);
}

// Fractal sum normalized by the amplitude total, so it stays in about [-1, 1]
// whatever the octave count.
inline float fbm(float x, float y, uint32_t seed, int octaves, float lacunarity = 2.0f,
                 float gain = 0.5f) {
  float sum = 0, amplitude = 1, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * gradientNoise(x, y, seed + 0x9e3779b9u * uint32_t(o));
    norm += amplitude;
    amplitude *= gain;
    x *= lacunarity;
    y *= lacunarity;
  }
  return sum / norm;
}

inline float fbm(Vec3f p, uint32_t seed, int octaves, float lacunarity = 2.0f, float gain = 0.5f) {
  float sum = 0, amplitude = 1, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * gradientNoise(p, seed + 0x9e3779b9u * uint32_t(o));
    norm += amplitude;
    amplitude *= gain;
    p = p * lacunarity;
  }
  return sum / norm;
}

}  // namespace ferry::builtin
