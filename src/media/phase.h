// The Henyey-Greenstein phase function, in pbrt's convention: `wo` points
// back along the arriving ray, `wi` towards where light comes from, and
// g > 0 scatters forwards (wi near -wo). Normalised over the sphere.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace ferry {

// The density (and value) for the cosine between the forward direction and wi.
inline float henyeyGreenstein(float cosForward, float g) {
  const float denom = 1 + g * g - 2 * g * cosForward;
  return (1 - g * g) / (4 * kPi * denom * std::sqrt(std::max(denom, 1e-12f)));
}

inline float phaseValue(Vec3f wo, Vec3f wi, float g) {
  return henyeyGreenstein(-dot(wo, wi), g);
}

// Samples wi from u in [0, 1)^2; returns its density (which is its value).
inline float samplePhase(Vec3f wo, float g, Vec2f u, Vec3f& wi) {
  float cosForward;
  if (std::abs(g) < 1e-3f) {
    cosForward = 1 - 2 * u.x;
  } else {
    const float s = (1 - g * g) / (1 - g + 2 * g * u.x);
    cosForward = std::clamp((1 + g * g - s * s) / (2 * g), -1.0f, 1.0f);
  }
  const float sinForward = std::sqrt(std::max(0.0f, 1 - cosForward * cosForward));
  const float phi = 2 * kPi * u.y;
  const Frame frame(-wo);
  wi = frame.toWorld({sinForward * std::cos(phi), sinForward * std::sin(phi), cosForward});
  return henyeyGreenstein(cosForward, g);
}

}  // namespace ferry
