// Textures: 8-bit RGBA texels (base colour, alpha cut-outs) with bilinear
// filtering and wrap modes, and float RGB images for environment lighting.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/math.h"
#include "core/shared_array.h"
#include "scene/solid_texture.h"

namespace ferry {

enum class WrapMode : uint8_t { Repeat, Clamp, Mirror };

// How a combined texture forms its value from its operands: pbrt's
// composite texture classes (directionmix as the mean of its two).
enum class TextureCombination : uint8_t { None, Scale, Mix, Checkerboard, Dots, Bilerp };

// An operand of a combined texture: a constant, or one of its parts.
struct TextureOperand {
  Vec3f constant{1};
  int32_t part = -1;  // index into Texture::parts; -1: the constant
};

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
  // is evaluated at the shading point.
  SolidTexture solid;
  // A combination of operands of which one at least is solid (pbrt's scale,
  // mix, checkerboard, dots, bilerp): evaluated at the shading point from its
  // parts, textures of their own. Operands: scale a * b; mix a, b by the
  // mean of c; checkerboard and dots a (even, inside), b; bilerp v00, v01,
  // v10, v11. `mapping` (su, sv, du, dv) maps uv for the patterns.
  TextureCombination combination = TextureCombination::None;
  Vec4f mapping{1, 1, 0, 0};
  std::array<TextureOperand, 4> operands;
  std::vector<Texture> parts;

  // Whether it is evaluated at the shading point (solid or combined) rather
  // than looked up in texels.
  bool isSolid() const {
    return solid.kind != SolidTextureKind::None || combination != TextureCombination::None;
  }
  // The value at a shading point, unclamped: the image at uv, the solid
  // texture at world point p, or the combination of its operands there.
  Vec3f value(Vec2f uv, Vec3f p) const;
  // The colour at a shading point: the image at uv, or value() with alpha 1
  // and negative values clamped to 0, as pbrt's materials clamp their
  // reflectances (fBm is negative half the time).
  Vec4f evaluate(Vec2f uv, Vec3f p) const {
    if (!isSolid()) return sample(uv);
    const Vec3f c = max(value(uv, p), Vec3f(0));
    return {c.x, c.y, c.z, 1};
  }
  // Drops texels and parts (a texture no shape on this rank uses).
  void release() {
    rgba.clear();
    parts.clear();
  }

  uint64_t texelCount() const { return uint64_t(width) * uint64_t(height); }
  bool hasTexels() const { return width > 0 && height > 0; }
  // Bilinear lookup at (u, v); v = 0 is the bottom row, as in OBJ and glTF-flipped uvs.
  Vec4f sample(Vec2f uv) const;
  // Alpha alone, cheaper than sample() for cut-out tests.
  float sampleAlpha(Vec2f uv) const { return hasTexels() ? alphaAt(taps(uv)) : 1.0f; }

  // The four texels a bilinear lookup at uv blends, after wrapping (columns
  // x0, x1, rows y0, y1), and its weights; (x0, y0) names the footprint.
  // Only for a texture with texels.
  struct Taps {
    int x0, x1, y0, y1;
    float fx, fy;
  };
  Taps taps(Vec2f uv) const;
  // sampleAlpha() from its taps.
  float alphaAt(const Taps& t) const;
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

// pbrt's 2D patterns at mapped coordinates st: the checkerboard's even
// squares, and whether st falls in a dot (pbrt-v3's DotsTexture: in each
// unit cell a dot of radius 0.35 where the noise at the cell is positive,
// its centre moved by noise).
bool checkerboardEven(Vec2f st);
bool insideDot(Vec2f st);

float srgbToLinear(float encoded);
float linearToSrgb(float linear);

}  // namespace ferry
