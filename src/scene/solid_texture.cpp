#include "scene/solid_texture.h"

#include <algorithm>
#include <cmath>

namespace ferry {

float fractalBrownianMotion(Vec3f p, float omega, int octaves) {
  float sum = 0, lambda = 1, o = 1;
  for (int i = 0; i < octaves; ++i) {
    sum += o * perlinNoise(p * lambda);
    lambda *= 1.99f;
    o *= omega;
  }
  return sum;
}

float turbulence(Vec3f p, float omega, int octaves) {
  float sum = 0, lambda = 1, o = 1;
  for (int i = 0; i < octaves; ++i) {
    sum += o * std::abs(perlinNoise(p * lambda));
    lambda *= 1.99f;
    o *= omega;
  }
  // pbrt-v3 adds its partial octave's term, which with no fraction left is
  // 0.2 (its estimate of |noise|'s mean) at the next weight.
  return sum + o * 0.2f;
}

namespace {

// pbrt-v3's marble: a cubic Bezier through four of nine colours, chosen by
// t, times 1.5. (One pbrt-v3 revision chose the segment by min(1, ...),
// which extrapolates the spline to reflectances of up to 40 for half the
// veins; its reference renders show the plain spline, which this is, with
// the segment kept in range at t = 1.)
Vec3f marbleColor(float t) {
  static const Vec3f c[9] = {{.58f, .58f, .6f}, {.58f, .58f, .6f}, {.58f, .58f, .6f},
                             {.5f, .5f, .5f},   {.6f, .59f, .58f}, {.58f, .58f, .6f},
                             {.58f, .58f, .6f}, {.2f, .2f, .33f},  {.58f, .58f, .6f}};
  constexpr int kSegments = 9 - 3;
  const int first = std::clamp(int(std::floor(t * kSegments)), 0, kSegments - 1);
  t = t * kSegments - float(first);
  const Vec3f c0 = c[first], c1 = c[first + 1], c2 = c[first + 2], c3 = c[first + 3];
  Vec3f s0 = c0 * (1 - t) + c1 * t, s1 = c1 * (1 - t) + c2 * t;
  const Vec3f s2 = c2 * (1 - t) + c3 * t;
  s0 = s0 * (1 - t) + s1 * t;
  s1 = s1 * (1 - t) + s2 * t;
  return (s0 * (1 - t) + s1 * t) * 1.5f;
}

}  // namespace

Vec3f SolidTexture::evaluate(Vec3f world) const {
  const Vec3f p = worldToTexture.transformPoint(world);
  switch (kind) {
    case SolidTextureKind::Marble: {
      const Vec3f q = p * scale;
      const float marble = q.y + variation * fractalBrownianMotion(q, omega, octaves);
      return marbleColor(0.5f + 0.5f * std::sin(marble));
    }
    case SolidTextureKind::Fbm:
      return Vec3f(fractalBrownianMotion(p, omega, octaves));
    case SolidTextureKind::Wrinkled:
      return Vec3f(turbulence(p, omega, octaves));
    case SolidTextureKind::Windy: {
      // pbrt-v3: wind strength from three slow octaves, wave height from six.
      const float strength = fractalBrownianMotion(p * 0.1f, 0.5f, 3);
      return Vec3f(std::abs(strength) * fractalBrownianMotion(p, 0.5f, 6));
    }
    case SolidTextureKind::None:
      break;
  }
  return Vec3f(1);
}

}  // namespace ferry
