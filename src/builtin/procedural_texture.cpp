#include "builtin/procedural_texture.h"

#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "builtin/noise.h"

namespace ferry::builtin {
namespace {

uint8_t toByte(float x) {
  return static_cast<uint8_t>(std::lround(std::clamp(x, 0.0f, 1.0f) * 255));
}

int wrapIndex(int i, int n) {
  return ((i % n) + n) % n;
}

// Gradient noise whose lattice repeats every (px, py) cells.
float periodicNoise(float x, float y, int px, int py, uint32_t seed) {
  float fx = std::floor(x), fy = std::floor(y);
  int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  float tx = x - fx, ty = y - fy;
  int x0 = wrapIndex(ix, px), x1 = wrapIndex(ix + 1, px);
  int y0 = wrapIndex(iy, py), y1 = wrapIndex(iy + 1, py);
  float n00 = detail::gradient2(seed, x0, y0, tx, ty);
  float n10 = detail::gradient2(seed, x1, y0, tx - 1, ty);
  float n01 = detail::gradient2(seed, x0, y1, tx, ty - 1);
  float n11 = detail::gradient2(seed, x1, y1, tx - 1, ty - 1);
  float u = detail::fade(tx), v = detail::fade(ty);
  return 1.4142f * lerpf(lerpf(n00, n10, u), lerpf(n01, n11, u), v);
}

float tileableFbm2(Vec2f uv, int periodU, int periodV, uint32_t seed, int octaves) {
  float sum = 0, amplitude = 1, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * periodicNoise(uv.x * float(periodU), uv.y * float(periodV), periodU, periodV,
                                     seed + 0x9e3779b9u * uint32_t(o));
    norm += amplitude;
    amplitude *= 0.5f;
    periodU *= 2;
    periodV *= 2;
  }
  return sum / norm;
}

Vec4f rgba(Vec3f c, float a) {
  return {c.x, c.y, c.z, a};
}

// An elongated leaf shape from `base` along `dir`; returns the distance from
// the midrib as a fraction of the local half width (>1: outside).
float leafShape(Vec2f p, Vec2f base, Vec2f dir, float length, float width, float& along) {
  Vec2f d = p - base;
  along = (d.x * dir.x + d.y * dir.y) / length;
  if (along < 0 || along > 1) return 2;
  float across = (d.x * -dir.y + d.y * dir.x) / (0.5f * width);
  if (std::abs(across) > 1) return 2;  // wider than any leaf: skip the shape
  float half =
      std::pow(std::sin(kPi * along), 0.7f) * (along < 0.5f ? 1.0f : 1.0f - 0.3f * (along - 0.5f));
  if (half <= 0) return 2;
  return std::abs(across) / half;
}

}  // namespace

Texture paintTexture(const std::string& name, int width, int height, WrapMode wrap,
                     const std::function<Vec4f(Vec2f)>& colourAt) {
  Texture t;
  t.name = name;
  t.width = width;
  t.height = height;
  t.wrap = wrap;
  t.srgb = true;
  t.rgba.resize(size_t(width) * size_t(height) * 4);
  tbb::parallel_for(0, height, [&](int y) {
    float v = 1.0f - (float(y) + 0.5f) / float(height);  // row 0 is the top (v = 1)
    uint8_t* row = &t.rgba[size_t(y) * size_t(width) * 4];
    for (int x = 0; x < width; ++x) {
      Vec4f c = colourAt({(float(x) + 0.5f) / float(width), v});
      row[4 * x + 0] = toByte(linearToSrgb(c.x));
      row[4 * x + 1] = toByte(linearToSrgb(c.y));
      row[4 * x + 2] = toByte(linearToSrgb(c.z));
      row[4 * x + 3] = toByte(c.w);
    }
  });
  return t;
}

float tileableFbm(Vec2f uv, int period, uint32_t seed, int octaves) {
  return tileableFbm2(uv, period, period, seed, octaves);
}

Texture leafClusterTexture(const std::string& name, int size, uint32_t seed, Vec3f light,
                           Vec3f dark, int leaves) {
  struct Leaf {
    Vec2f base, dir;
    float length, width, shade;
  };
  std::vector<Leaf> shapes;
  HashRng rng(seed, 0x1eaf);
  for (int k = 0; k < leaves; ++k) {
    float t = leaves == 1 ? 0.5f : float(k) / float(leaves - 1);
    float side = k % 2 == 0 ? 1.0f : -1.0f;
    float angle = side * rng.uniform(0.6f, 1.0f) * (1.0f - 0.5f * t);
    float length = 0.34f * (1.0f - 0.35f * t) * rng.uniform(0.85f, 1.1f);
    shapes.push_back({{0.5f, 0.04f + 0.78f * t},
                      {std::sin(angle), std::cos(angle)},
                      length,
                      0.42f * length,
                      rng.uniform(0, 1)});
  }
  shapes.push_back({{0.5f, 0.8f}, {0, 1}, 0.19f, 0.09f, rng.uniform(0, 1)});  // terminal leaf
  const Vec3f twig{0.12f, 0.08f, 0.04f};
  const Vec3f average = (light + dark) * 0.5f;
  return paintTexture(name, size, size, WrapMode::Clamp, [&](Vec2f uv) {
    for (int k = int(shapes.size()) - 1; k >= 0; --k) {  // later leaves lie on top
      const Leaf& l = shapes[k];
      float along;
      float r = leafShape(uv, l.base, l.dir, l.length, l.width, along);
      if (r > 1) continue;
      float n = tileableFbm(uv, 16, seed + uint32_t(k), 3);
      Vec3f c = lerp(dark, light, std::clamp(0.25f + 0.5f * l.shade + 0.25f * n, 0.0f, 1.0f));
      if (r < 0.07f) c = c * 1.35f;                              // midrib
      c = c * (1.0f - 0.25f * r * r) * (0.85f + 0.15f * along);  // darker edges
      float vein = std::abs(std::sin(18.0f * (along + 0.5f * r)));
      c = c * (0.93f + 0.07f * vein);
      return rgba(c, 1);
    }
    if (std::abs(uv.x - 0.5f) < 0.008f && uv.y < 0.86f) return rgba(twig, 1);
    return rgba(average, 0);
  });
}

Texture frondTexture(const std::string& name, int width, int height, uint32_t seed, Vec3f light,
                     Vec3f dark, int leaflets, float leafletLength) {
  struct Leaflet {
    float v, length, sinAngle, cosAngle, shade;
  };
  std::vector<Leaflet> shapes;
  HashRng rng(seed, 0xf20d);
  for (int k = 0; k < leaflets; ++k) {
    float t = 0.03f + 0.95f * float(k) / float(leaflets);
    float envelope = std::pow(std::sin(kPi * (0.12f + 0.86f * t)), 0.6f);
    float length = leafletLength * envelope * rng.uniform(0.85f, 1.05f);
    float angle = rng.uniform(0.75f, 0.95f);
    shapes.push_back({t, length, std::sin(angle), std::cos(angle), rng.uniform(0, 1)});
  }
  const Vec3f rachis = dark * 0.7f + Vec3f(0.05f, 0.04f, 0.0f);
  return paintTexture(name, width, height, WrapMode::Clamp, [&](Vec2f uv) {
    float side = uv.x < 0.5f ? -1.0f : 1.0f;
    if (std::abs(uv.x - 0.5f) < 0.012f * (1.2f - uv.y)) return rgba(rachis, 1);
    for (const Leaflet& l : shapes) {
      // Leaflets run outwards and towards the tip; in uv units the card is
      // 1 wide, each side 0.5.
      // Leaflets point upwards: skip those that cannot reach this row.
      if (uv.y < l.v - 0.03f || uv.y > l.v + l.length + 0.03f) continue;
      Vec2f dir{side * l.sinAngle, l.cosAngle};
      float along;
      float r = leafShape(uv, {0.5f, l.v}, dir, l.length, 0.045f, along);
      if (r > 1) continue;
      Vec3f c = lerp(dark, light, std::clamp(0.3f + 0.4f * l.shade + 0.3f * along, 0.0f, 1.0f));
      if (r < 0.15f) c = c * 1.2f;
      return rgba(c, 1);
    }
    return rgba((light + dark) * 0.5f, 0);
  });
}

Texture needleTexture(const std::string& name, int size, uint32_t seed, Vec3f light, Vec3f dark) {
  HashRng rng(seed, 0x9eed);
  constexpr int kNeedles = 56;
  std::vector<float> jitter(2 * kNeedles);
  for (float& j : jitter) j = rng.uniform(-0.5f, 0.5f);
  const Vec3f twig{0.14f, 0.09f, 0.05f};
  return paintTexture(name, size, size, WrapMode::Clamp, [&](Vec2f uv) {
    if (std::abs(uv.x - 0.5f) < 0.01f && uv.y < 0.95f) return rgba(twig, 1);
    float side = uv.x < 0.5f ? -1.0f : 1.0f;
    float angle = 0.95f;
    Vec2f dir{side * std::sin(angle), std::cos(angle)};
    for (int k = 0; k < kNeedles; ++k) {
      float v0 = 0.02f + 0.9f * (float(k) + 0.5f + 0.4f * jitter[2 * k + (side > 0)]) / kNeedles;
      Vec2f d = uv - Vec2f{0.5f, v0};
      float along = d.x * dir.x + d.y * dir.y;
      float length = 0.42f * (1.0f - 0.4f * v0);
      if (along < 0 || along > length) continue;
      float across = std::abs(d.x * -dir.y + d.y * dir.x);
      if (across > 0.007f * (1.0f - 0.6f * along / length)) continue;
      return rgba(lerp(dark, light, along / length), 1);
    }
    return rgba((light + dark) * 0.5f, 0);
  });
}

Texture petalTexture(const std::string& name, int size, Vec3f tint) {
  const Vec3f white{0.85f, 0.85f, 0.85f};
  return paintTexture(name, size, size, WrapMode::Clamp, [&](Vec2f uv) {
    float half =
        0.47f * std::pow(std::sin(kPi * std::pow(std::clamp(uv.y, 0.0f, 1.0f), 0.6f)), 0.8f);
    float x = std::abs(uv.x - 0.5f);
    if (x > half || uv.y > 0.985f) return rgba(white, 0);
    float vein = 1.0f - 0.1f * std::abs(std::sin(30.0f * (uv.x - 0.5f) / std::max(half, 0.05f)));
    Vec3f c = lerp(tint, white, smoothstep(0.0f, 0.35f, uv.y)) * vein;
    return rgba(c, 1);
  });
}

Texture barkTexture(const std::string& name, int width, int height, uint32_t seed, Vec3f dark,
                    Vec3f light, BarkStyle style) {
  return paintTexture(name, width, height, WrapMode::Repeat, [=](Vec2f uv) {
    switch (style) {
      case BarkStyle::Birch: {
        float base = 0.5f + 0.5f * tileableFbm2(uv, 4, 4, seed, 3);
        float marks = tileableFbm2(uv, 6, 40, seed + 7, 2);
        Vec3f c = lerp(light * 0.85f, light, base);
        if (marks > 0.35f) c = lerp(c, dark, smoothstep(0.35f, 0.5f, marks));
        return rgba(c, 1);
      }
      case BarkStyle::PalmRings: {
        float n = tileableFbm2(uv, 8, 8, seed, 3);
        float ring = 0.5f + 0.5f * std::cos(2 * kPi * (uv.y * 16 + 0.15f * n));
        return rgba(lerp(dark, light, std::clamp(0.2f + 0.6f * ring + 0.2f * n, 0.0f, 1.0f)), 1);
      }
      case BarkStyle::Furrowed:
      default: {
        float ridge = 1.0f - std::abs(tileableFbm2(uv, 10, 3, seed, 4));
        float grain = tileableFbm2(uv, 32, 32, seed + 3, 2);
        return rgba(lerp(dark, light, std::clamp(ridge * ridge + 0.15f * grain, 0.0f, 1.0f)), 1);
      }
    }
  });
}

Texture rockTexture(const std::string& name, int size, uint32_t seed, Vec3f dark, Vec3f light) {
  return paintTexture(name, size, size, WrapMode::Repeat, [=](Vec2f uv) {
    float n = tileableFbm(uv, 6, seed, 5);
    float speckle = tileableFbm(uv, 96, seed + 11, 1);
    float t = std::clamp(0.5f + 0.6f * n + 0.15f * speckle, 0.0f, 1.0f);
    return rgba(lerp(dark, light, t), 1);
  });
}

Texture sandTexture(const std::string& name, int size, uint32_t seed, Vec3f dark, Vec3f light) {
  return paintTexture(name, size, size, WrapMode::Repeat, [=](Vec2f uv) {
    float n = tileableFbm(uv, 4, seed, 3);
    float grain = tileableFbm(uv, 128, seed + 5, 1);
    float t = std::clamp(0.55f + 0.35f * n + 0.2f * grain, 0.0f, 1.0f);
    return rgba(lerp(dark, light, t), 1);
  });
}

Texture bladeTexture(const std::string& name, int width, int height, uint32_t seed, Vec3f base,
                     Vec3f tip) {
  return paintTexture(name, width, height, WrapMode::Repeat, [=](Vec2f uv) {
    float streak = tileableFbm2(uv, 24, 2, seed, 2);
    Vec3f c = lerp(base, tip, std::pow(uv.y, 0.8f)) * (0.88f + 0.12f * streak);
    return rgba(c, 1);
  });
}

std::shared_ptr<const HdrImage> skyGradient(Vec3f zenith, Vec3f horizon, Vec3f below,
                                            float belowFade) {
  auto sky = std::make_shared<HdrImage>();
  sky->name = "sky-gradient";
  sky->width = 128;
  sky->height = 64;
  sky->pixels.resize(size_t(sky->width) * sky->height);
  for (int y = 0; y < sky->height; ++y) {
    float theta = kPi * (float(y) + 0.5f) / float(sky->height);  // row 0 is the zenith
    float elevation = kPi / 2 - theta;
    Vec3f c = elevation >= 0 ? lerp(horizon, zenith, std::pow(std::sin(elevation), 0.5f))
                             : lerp(horizon, below, smoothstep(0.0f, belowFade, -elevation));
    for (int x = 0; x < sky->width; ++x) sky->pixels[size_t(y) * sky->width + x] = c;
  }
  return sky;
}

}  // namespace ferry::builtin
