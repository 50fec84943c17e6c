// Textures: 8-bit RGBA texels (base colour, alpha cut-outs) with bilinear
// filtering and wrap modes, and float RGB images for environment lighting.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/shared_array.h"
#include "scene/solid_texture.h"

namespace ferry {

enum class WrapMode : uint8_t { Repeat, Clamp, Mirror };

struct Texture {
  std::string name;  // file name or generator name, for messages
  int width = 0;
  int height = 0;
  WrapMode wrap = WrapMode::Repeat;
  // Colour channels hold sRGB-encoded values; sample() returns linear colour.
  bool srgb = true;
  // width * height * 4, row 0 at the top (v = 1); owned, or shared with a
  // rank's mapped part file (core/shared_array.h)
  SharedArray<uint8_t> rgba;
  // A solid texture (pbrt's marble, fbm, wrinkled, windy) has no texels: it
  // is evaluated at the shading point (evaluate()).
  SolidTexture solid;

  bool isSolid() const { return solid.kind != SolidTextureKind::None; }
  // The colour at a shading point: the image at uv, or the solid texture at
  // world point p (alpha 1; negative values clamped to 0, as pbrt's
  // materials clamp their reflectances: fBm is negative half the time).
  Vec4f evaluate(Vec2f uv, Vec3f p) const {
    if (!isSolid()) return sample(uv);
    const Vec3f c = max(solid.evaluate(p), Vec3f(0));
    return {c.x, c.y, c.z, 1};
  }

  uint64_t texelCount() const { return uint64_t(width) * uint64_t(height); }
  // Bilinear lookup at (u, v); v = 0 is the bottom row, as in OBJ and glTF-flipped uvs.
  Vec4f sample(Vec2f uv) const;
  // Alpha alone, cheaper than sample() for cut-out tests.
  float sampleAlpha(Vec2f uv) const;
};

// Linear float RGB image, e.g. an equirectangular environment.
struct HdrImage {
  std::string name;
  int width = 0;
  int height = 0;
  std::vector<Vec3f> pixels;  // row-major, row 0 at the top

  Vec3f at(int x, int y) const { return pixels[size_t(y) * width + x]; }
  Vec3f sampleBilinear(Vec2f uv) const;
};

float srgbToLinear(float encoded);
float linearToSrgb(float linear);

}  // namespace ferry
