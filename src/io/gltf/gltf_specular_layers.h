// How glTF's specular layers become Ferry's one coat over a diffuse base
// (a layered CoatedDiffuseModel's specular, roughness and eta). At
// normal incidence the coat reflects exactly glTF's specularFactor
// min(F0 specularColor, 1), F0 from the ior; KHR_materials_clearcoat is mixed
// into the same coat by clearcoatFactor (each layer exact at 0 and 1). The
// formulas and what they approximate: docs/formats.md, "glTF".
#pragma once

#include "core/math.h"

namespace ferry {

struct GltfSpecularLayers {
  float ior = 1.5f;              // 0, or at least 1
  float roughness = 1;           // the material's (glTF and Ferry: GGX alpha = roughness^2)
  Vec3f specularColor{1, 1, 1};  // KHR_materials_specular, linear, each >= 0
  float specularFactor = 1;      // in [0, 1]
  float clearcoat = 0;           // KHR_materials_clearcoat, in [0, 1]
  float clearcoatRoughness = 0;  // in [0, 1]
};

struct FerryCoat {
  Vec3f tint{0, 0, 0};  // 0: no coat (a diffuse material)
  float roughness = 1;
  float eta = 1.5f;
};

FerryCoat ferryCoatOf(const GltfSpecularLayers& layers);

// Normal-incidence reflectance of a dielectric interface of relative index
// `eta` (0 gives 1: glTF's legacy ior), and its inverse (f0 in [0, 1)).
float f0OfEta(float eta);
float etaOfF0(float f0);

}  // namespace ferry
