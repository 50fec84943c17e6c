// pbrt's solid (3D) textures: evaluated at the shading point, not baked over
// uv, since they are functions of space (a marble table top is veined across
// its faces whatever its uv). Perlin's improved noise with pbrt-v3's gradient
// choice, fBm and turbulence as pbrt-v3 sums them, and the textures built on
// them: marble, fbm, wrinkled, windy.
//
// pbrt limits the octaves by the ray differentials' footprint (antialiasing);
// Ferry's paths carry no differentials, so every octave is summed (what pbrt
// does for a footprint below the finest octave). The mean colour is the same;
// the finest detail is not filtered.
#pragma once

#include <cstdint>

#include "core/math.h"
#include "core/perlin_noise.h"

namespace ferry {

enum class SolidTextureKind : uint8_t { None, Marble, Fbm, Wrinkled, Windy };

// The parameters pbrt's solid textures take, with pbrt-v3's defaults.
struct SolidTexture {
  SolidTextureKind kind = SolidTextureKind::None;
  Affine3f worldToTexture;  // the texture's space (pbrt: its CTM at definition)
  int32_t octaves = 8;
  float omega = 0.5f;      // "roughness": each octave's weight relative to the last
  float scale = 1;         // marble: of the texture space
  float variation = 0.2f;  // marble: of the veins

  // The texture's value at world point `p` (linear RGB; the float textures
  // give grey).
  Vec3f evaluate(Vec3f p) const;
};

// Sums of `octaves` octaves (frequency x1.99, weight x omega), as pbrt-v3's
// FBm and Turbulence with every octave taken (turbulence then adds pbrt's
// 0.2 for the next octave).
float fractalBrownianMotion(Vec3f p, float omega, int octaves);
float turbulence(Vec3f p, float omega, int octaves);

}  // namespace ferry
