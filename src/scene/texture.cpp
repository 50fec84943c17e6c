#include "scene/texture.h"

#include <array>
#include <cmath>

#include "core/perlin_noise.h"

namespace ferry {
namespace {

int wrapCoordinate(int i, int n, WrapMode mode) {
  switch (mode) {
    case WrapMode::Clamp:
      return std::clamp(i, 0, n - 1);
    case WrapMode::Mirror: {
      int period = 2 * n;
      int m = ((i % period) + period) % period;
      return m < n ? m : period - 1 - m;
    }
    case WrapMode::Repeat:
    default:
      return ((i % n) + n) % n;
  }
}

// 8-bit sRGB to linear, tabulated once: textures are sampled many times per path.
const std::array<float, 256>& srgbTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = srgbToLinear(i / 255.0f);
    return t;
  }();
  return table;
}

using BilinearTaps = Texture::Taps;

BilinearTaps bilinearTaps(Vec2f uv, int width, int height, WrapMode wrapX, WrapMode wrapY) {
  // Texel centres sit at half-integers; v = 0 is the bottom of the image.
  float x = uv.x * width - 0.5f;
  float y = (1.0f - uv.y) * height - 0.5f;
  if (!std::isfinite(x)) x = 0;
  if (!std::isfinite(y)) y = 0;
  float fx0 = std::floor(x), fy0 = std::floor(y);
  // Keep huge uvs from overflowing int.
  fx0 = std::fmod(fx0, 1 << 24);
  fy0 = std::fmod(fy0, 1 << 24);
  int ix = static_cast<int>(fx0), iy = static_cast<int>(fy0);
  return {wrapCoordinate(ix, width, wrapX),
          wrapCoordinate(ix + 1, width, wrapX),
          wrapCoordinate(iy, height, wrapY),
          wrapCoordinate(iy + 1, height, wrapY),
          x - std::floor(x),
          y - std::floor(y)};
}

}  // namespace

float srgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1 / 2.4f) - 0.055f;
}

Vec4f Texture::sample(Vec2f uv) const {
  if (!hasTexels()) return {1, 1, 1, 1};
  BilinearTaps t = bilinearTaps(uv, width, height, wrap, wrap);
  const auto& table = srgbTable();
  auto fetch = [&](int x, int y) {
    const uint8_t* p = &rgba[(size_t(y) * width + x) * 4];
    if (srgb) return Vec4f{table[p[0]], table[p[1]], table[p[2]], p[3] / 255.0f};
    return Vec4f{p[0] / 255.0f, p[1] / 255.0f, p[2] / 255.0f, p[3] / 255.0f};
  };
  Vec4f a = fetch(t.x0, t.y0), b = fetch(t.x1, t.y0), c = fetch(t.x0, t.y1), d = fetch(t.x1, t.y1);
  auto mix = [&](float va, float vb, float vc, float vd) {
    return (va * (1 - t.fx) + vb * t.fx) * (1 - t.fy) + (vc * (1 - t.fx) + vd * t.fx) * t.fy;
  };
  return {mix(a.x, b.x, c.x, d.x), mix(a.y, b.y, c.y, d.y), mix(a.z, b.z, c.z, d.z),
          mix(a.w, b.w, c.w, d.w)};
}

Texture::Taps Texture::taps(Vec2f uv) const {
  return bilinearTaps(uv, width, height, wrap, wrap);
}

float Texture::alphaAt(const Taps& t) const {
  auto alpha = [&](int x, int y) { return rgba[(size_t(y) * width + x) * 4 + 3] / 255.0f; };
  return (alpha(t.x0, t.y0) * (1 - t.fx) + alpha(t.x1, t.y0) * t.fx) * (1 - t.fy) +
         (alpha(t.x0, t.y1) * (1 - t.fx) + alpha(t.x1, t.y1) * t.fx) * t.fy;
}

bool checkerboardEven(Vec2f st) {
  return (long(std::floor(st.x)) + long(std::floor(st.y))) % 2 == 0;
}

bool insideDot(Vec2f st) {
  const float s = std::floor(st.x + 0.5f), u = std::floor(st.y + 0.5f);
  if (!(perlinNoise({s + 0.5f, u + 0.5f, 0.5f}) > 0)) return false;
  constexpr float kRadius = 0.35f, kMaxShift = 0.5f - kRadius;
  const float sCenter = s + kMaxShift * perlinNoise({s + 1.5f, u + 2.8f, 0.5f});
  const float uCenter = u + kMaxShift * perlinNoise({s + 4.5f, u + 9.8f, 0.5f});
  const float ds = st.x - sCenter, du = st.y - uCenter;
  return ds * ds + du * du < kRadius * kRadius;
}

Vec3f Texture::value(Vec2f uv, Vec3f p) const {
  if (solid.kind != SolidTextureKind::None) return solid.evaluate(p);
  if (combination == TextureCombination::None) return sample(uv).xyz();
  auto operand = [&](int i) {
    const TextureOperand& o = operands[size_t(i)];
    return o.part < 0 ? o.constant : parts[size_t(o.part)].value(uv, p);
  };
  const Vec2f st{mapping.x * uv.x + mapping.z, mapping.y * uv.y + mapping.w};
  switch (combination) {
    case TextureCombination::Scale:
      return operand(0) * operand(1);
    case TextureCombination::Mix: {
      const Vec3f amount = operand(2);
      return lerp(operand(0), operand(1), (amount.x + amount.y + amount.z) / 3);
    }
    case TextureCombination::Checkerboard:
      return checkerboardEven(st) ? operand(0) : operand(1);
    case TextureCombination::Dots:
      return insideDot(st) ? operand(0) : operand(1);
    case TextureCombination::Bilerp: {
      const float s = st.x - std::floor(st.x), t = st.y - std::floor(st.y);
      return lerp(lerp(operand(0), operand(2), s), lerp(operand(1), operand(3), s), t);
    }
    case TextureCombination::None:
      break;
  }
  return Vec3f(1);
}

Vec3f HdrImage::sampleBilinear(Vec2f uv) const {
  if (width <= 0 || height <= 0) return Vec3f(0);
  // Longitude wraps around, latitude stops at the poles.
  BilinearTaps t = bilinearTaps(uv, width, height, WrapMode::Repeat, WrapMode::Clamp);
  return lerp(lerp(at(t.x0, t.y0), at(t.x1, t.y0), t.fx),
              lerp(at(t.x0, t.y1), at(t.x1, t.y1), t.fx), t.fy);
}

}  // namespace ferry
