// Perlin's improved noise as pbrt's Noise() computes it (Perlin's 2002
// permutation, pbrt-v3's gradient choice): 0 at the lattice points, in about
// [-1, 1], period 256. Solid textures and pbrt-v4's cloud medium use it.
#pragma once

#include "core/math.h"

namespace ferry {

float perlinNoise(Vec3f p);
// pbrt-v4's DNoise: the noise's slope by forward differences 0.01 apart.
Vec3f perlinNoiseSlope(Vec3f p);

}  // namespace ferry
