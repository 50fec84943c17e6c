#include "io/gltf/gltf_specular_layers.h"

#include <algorithm>
#include <cmath>

namespace ferry {
namespace {

// F0 = 1 would need an infinite index; 0.99 is eta 399, a near-mirror.
constexpr float kMaxF0 = 0.99f;
constexpr float kClearcoatEta = 1.5f;  // KHR_materials_clearcoat's fixed F0 of 0.04

float mix(float a, float b, float t) {
  return a + (b - a) * t;
}

FerryCoat specularLayer(const GltfSpecularLayers& layers) {
  FerryCoat coat;
  coat.roughness = layers.roughness;
  const float f0 = f0OfEta(layers.ior);
  const Vec3f f0c = min(layers.specularColor * f0, Vec3f(1));
  const float peak = maxComponent(f0c);
  if (!(peak > 0) || !(layers.specularFactor > 0)) return coat;  // no specular layer
  if (layers.ior >= 1 && maxComponent(layers.specularColor) == 1) {
    // The usual case, kept exact rather than through F0 and back.
    coat.eta = layers.ior;
    coat.tint = layers.specularColor * layers.specularFactor;
    return coat;
  }
  coat.eta = etaOfF0(std::min(peak, kMaxF0));
  coat.tint = f0c * (layers.specularFactor / peak);
  return coat;
}

}  // namespace

float f0OfEta(float eta) {
  const float r = (eta - 1) / (eta + 1);
  return r * r;
}

float etaOfF0(float f0) {
  const float r = std::sqrt(std::clamp(f0, 0.0f, kMaxF0));
  return (1 + r) / (1 - r);
}

FerryCoat ferryCoatOf(const GltfSpecularLayers& layers) {
  FerryCoat coat = specularLayer(layers);
  const float c = layers.clearcoat;
  if (!(c > 0)) return coat;
  coat.tint = coat.tint * (1 - c) + Vec3f(c);
  coat.eta = mix(coat.eta, kClearcoatEta, c);
  coat.roughness = mix(coat.roughness, layers.clearcoatRoughness, c);
  return coat;
}

}  // namespace ferry
