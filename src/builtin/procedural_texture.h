// Generated 8-bit RGBA textures for the built-in scenes: leaf, frond, needle
// and petal cards with an alpha cut-out, and tileable bark, rock, sand and
// grass. Colours are given in linear RGB and stored sRGB-encoded (srgb = true),
// as image files would be. Every texture is a pure function of its arguments.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "core/math.h"
#include "scene/texture.h"

namespace ferry::builtin {

// A vertical sky for an equirectangular environment: horizon to zenith above,
// fading to `below` under the horizon over `belowFade` radians.
std::shared_ptr<const HdrImage> skyGradient(Vec3f zenith, Vec3f horizon, Vec3f below,
                                            float belowFade);

// Paints width x height texels from `colourAt(uv)` (linear rgb, alpha in w),
// evaluated at texel centres with v = 0 at the bottom row, rows in parallel.
Texture paintTexture(const std::string& name, int width, int height, WrapMode wrap,
                     const std::function<Vec4f(Vec2f)>& colourAt);

// Tileable fractal noise in about [-1, 1] over the unit square: `period`
// lattice cells across at the first octave, so u = 0 and u = 1 match (tubes
// wrap their u around, and repeated uvs tile without seams).
float tileableFbm(Vec2f uv, int period, uint32_t seed, int octaves);

// A twig along v with `leaves` leaves on alternate sides (alpha 0 around them).
Texture leafClusterTexture(const std::string& name, int size, uint32_t seed, Vec3f light,
                           Vec3f dark, int leaves);
// A palm or fern frond: a rachis along v at u = 0.5 with leaflets on both sides.
Texture frondTexture(const std::string& name, int width, int height, uint32_t seed, Vec3f light,
                     Vec3f dark, int leaflets, float leafletLength);
// A conifer twig: dense needles at an angle on both sides of a centre line.
Texture needleTexture(const std::string& name, int size, uint32_t seed, Vec3f light, Vec3f dark);
// One petal from its base (v = 0) to its tip, nearly white so the material
// colour tints it; `tint` colours the base.
Texture petalTexture(const std::string& name, int size, Vec3f tint);

enum class BarkStyle : uint8_t { Furrowed, Birch, PalmRings };
Texture barkTexture(const std::string& name, int width, int height, uint32_t seed, Vec3f dark,
                    Vec3f light, BarkStyle style);
Texture rockTexture(const std::string& name, int size, uint32_t seed, Vec3f dark, Vec3f light);
Texture sandTexture(const std::string& name, int size, uint32_t seed, Vec3f dark, Vec3f light);
// Along v: dark at the base to light at the tip, with fine streaks across u.
Texture bladeTexture(const std::string& name, int width, int height, uint32_t seed, Vec3f base,
                     Vec3f tip);

}  // namespace ferry::builtin
