// Arbitrary output variables (AOVs, --aov): per-pixel features of the
// surface each camera ray meets first, averaged over the pixel's samples
// exactly as its colour is (a miss adds zero: pbrt-v4's gbuffer film does
// the same). They are what denoisers take beside the colour (Open Image
// Denoise, OptiX: albedo and normal). Names and channel names follow
// pbrt-v4's gbuffer film (Albedo.R, Ns.X, N.X, P.X, u, v), in world space;
// depth is OpenEXR's Z channel. docs/guide.md, "AOVs".
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/math.h"

namespace ferry {

enum class Aov {
  Albedo,           // the BSDF's directional albedo, one sample a sample, in [0, 1]
  Normal,           // the shading normal, turned as shading turns it (towards the camera)
  GeometricNormal,  // the triangle's normal, turned the same way
  Depth,            // the camera ray's length to the hit (from the lens point)
  Position,         // the hit, world space
  Uv,               // the surface's texture coordinates
};

struct AovSpec {
  Aov aov;
  const char* name;  // as --aov takes it
  int channels;
  std::array<const char*, 3> channelNames;  // the EXR channels (the first `channels`)
};

inline constexpr std::array<AovSpec, 6> kAovSpecs = {{
    {Aov::Albedo, "albedo", 3, {"Albedo.R", "Albedo.G", "Albedo.B"}},
    {Aov::Normal, "normal", 3, {"Ns.X", "Ns.Y", "Ns.Z"}},
    {Aov::GeometricNormal, "geometric-normal", 3, {"N.X", "N.Y", "N.Z"}},
    {Aov::Depth, "depth", 1, {"Z", nullptr, nullptr}},
    {Aov::Position, "position", 3, {"P.X", "P.Y", "P.Z"}},
    {Aov::Uv, "uv", 2, {"u", "v", nullptr}},
}};

inline const AovSpec& aovSpec(Aov aov) {
  return kAovSpecs[size_t(aov)];
}

// "albedo,normal,depth" -> the AOVs in that order; throws InputError naming
// an unknown or repeated name and listing the known ones. Empty: none.
std::vector<Aov> parseAovList(const std::string& text);
// The names, comma-separated (parseAovList's inverse).
std::string aovListText(const std::vector<Aov>& aovs);
// Channels a pixel has for `aovs`, all together.
int aovChannelCount(const std::vector<Aov>& aovs);
// The Aov named `name`, false if none is.
bool aovNamed(const std::string& name, Aov& out);

// One AOV of `values` (aovChannelCount(aovs) floats a pixel, the AOVs in
// order; `shown` must be among them) as an RGBA8 picture to look at:
// albedo and uv as colours (sRGB), normals as 0.5 + 0.5 n, depth and
// position scaled by their range over the image (depth: near is bright).
std::vector<uint8_t> aovPicture(const std::vector<float>& values, const std::vector<Aov>& aovs,
                                Aov shown, size_t pixels);

// What one camera sample's first surface gives the AOVs.
struct SurfaceAovs {
  Vec3f albedo;
  Vec3f shadingNormal;
  Vec3f geometricNormal;
  float depth = 0;
  Vec3f position;
  Vec2f uv;
};

}  // namespace ferry
