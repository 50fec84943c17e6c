// The metallic-roughness description of a surface (glTF's core material,
// Disney's principled BSDF as pbrt-v3 names it, MTL's PBR extension) mapped
// onto a material model: the dominant parameter picks it, so a blend of
// metal and dielectric takes the larger (glass at transmission >= 0.5, else
// a conductor at metallic >= 0.5, else a diffuse base, coated if a coat is
// given).
#pragma once

#include <memory>

#include "core/math.h"
#include "material/material_model.h"

namespace ferry {

struct MetallicRoughness {
  float metallic = 0;      // [0, 1]
  float roughness = 1;     // [0, 1], Ferry's (GGX alpha = roughness^2)
  float transmission = 0;  // [0, 1]
  float ior = 1.5f;        // the glass's
  // A dielectric coat over the base (glTF's specular layer and clear coat,
  // MTL's Ks): its tint (black: none), roughness and relative index.
  Vec3f coat{0};
  float coatRoughness = 0.3f;
  float coatEta = 1.5f;
  bool coatLayered = true;  // the base seen through the coat; false: base + coat
};

std::shared_ptr<const MaterialModel> modelOf(const MetallicRoughness& surface);

}  // namespace ferry
