#include "core/perlin_noise.h"

#include <cmath>
#include <cstdint>

namespace ferry {
namespace {

// Ken Perlin's permutation ("Improved Noise", 2002), the table pbrt uses,
// twice over so that indices up to 511 need no wrap.
constexpr uint8_t kPermutation[256] = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103,
    30,  69,  142, 8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,
    197, 62,  94,  252, 219, 203, 117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174,
    20,  125, 136, 171, 168, 68,  175, 74,  165, 71,  134, 139, 48,  27,  166, 77,  146, 158, 231,
    83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,  55,  46,  245, 40,  244, 102, 143,
    54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,  18,  169, 200, 196,
    135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250, 124,
    123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,
    182, 189, 28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101,
    155, 167, 43,  172, 9,   129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185,
    112, 104, 218, 246, 97,  228, 251, 34,  242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,
    51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,  181, 199, 106, 157, 184, 84,  204, 176,
    115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114, 67,  29,  24,  72,  243,
    141, 128, 195, 78,  66,  215, 61,  156, 180};

int permutation(int i) {
  return kPermutation[i & 255];
}

// The gradient at lattice point (x, y, z) dotted with the offset: one of 12
// edge directions of a cube (pbrt-v3's choice for hashes 12 and 13).
float gradient(int x, int y, int z, float dx, float dy, float dz) {
  const int h = permutation(permutation(permutation(x) + y) + z) & 15;
  const float u = h < 8 || h == 12 || h == 13 ? dx : dy;
  const float v = h < 4 || h == 12 || h == 13 ? dy : dz;
  return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

// 6t^5 - 15t^4 + 10t^3: zero first and second derivatives at the lattice.
float fade(float t) {
  const float t3 = t * t * t, t4 = t3 * t;
  return 6 * t4 * t - 15 * t4 + 10 * t3;
}

float mix(float t, float a, float b) {
  return (1 - t) * a + t * b;
}

}  // namespace

float perlinNoise(Vec3f p) {
  const float fx = std::floor(p.x), fy = std::floor(p.y), fz = std::floor(p.z);
  const float dx = p.x - fx, dy = p.y - fy, dz = p.z - fz;
  // Lattice coordinates modulo 256 (the table's period), also for negative ones.
  const int ix = int(int64_t(fx) & 255), iy = int(int64_t(fy) & 255), iz = int(int64_t(fz) & 255);
  const float w000 = gradient(ix, iy, iz, dx, dy, dz);
  const float w100 = gradient(ix + 1, iy, iz, dx - 1, dy, dz);
  const float w010 = gradient(ix, iy + 1, iz, dx, dy - 1, dz);
  const float w110 = gradient(ix + 1, iy + 1, iz, dx - 1, dy - 1, dz);
  const float w001 = gradient(ix, iy, iz + 1, dx, dy, dz - 1);
  const float w101 = gradient(ix + 1, iy, iz + 1, dx - 1, dy, dz - 1);
  const float w011 = gradient(ix, iy + 1, iz + 1, dx, dy - 1, dz - 1);
  const float w111 = gradient(ix + 1, iy + 1, iz + 1, dx - 1, dy - 1, dz - 1);
  const float wx = fade(dx), wy = fade(dy), wz = fade(dz);
  const float y0 = mix(wy, mix(wx, w000, w100), mix(wx, w010, w110));
  const float y1 = mix(wy, mix(wx, w001, w101), mix(wx, w011, w111));
  return mix(wz, y0, y1);
}

Vec3f perlinNoiseSlope(Vec3f p) {
  constexpr float kDelta = 0.01f;
  const float n = perlinNoise(p);
  return Vec3f(perlinNoise(p + Vec3f(kDelta, 0, 0)) - n, perlinNoise(p + Vec3f(0, kDelta, 0)) - n,
               perlinNoise(p + Vec3f(0, 0, kDelta)) - n) *
         (1 / kDelta);
}

}  // namespace ferry
