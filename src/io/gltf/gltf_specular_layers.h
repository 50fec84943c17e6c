// How glTF's specular layers become Ferry's one coat over a diffuse base
// (Material::specular, specularRoughness, specularEta with Coat::Layered).
//
// glTF's dielectric (non-metallic) material is a diffuse base under a
// specular layer of the material's roughness whose Fresnel term has
// F0 = ((ior - 1) / (ior + 1))^2 (0.04 at the default ior 1.5;
// KHR_materials_ior sets the ior, 0 meaning the legacy F0 = 1), tinted and
// scaled by KHR_materials_specular:
//   F = specularFactor (F0c + (1 - F0c) (1 - cos)^5),  F0c = min(F0 specularColor, 1),
// and the base is weighted by 1 - max3(F). Ferry's Layered coat reflects
// tint * F_eta(cos) (the dielectric Fresnel term of relative index eta) and
// weights the base by (1 - F_eta(wo)) (1 - F_eta(wi)). So:
//   eta  = the index whose F0 is the largest channel of F0c (the ior itself
//          when the specular colour's largest channel is 1, as in every file
//          without KHR_materials_specular); at most F0 0.99;
//   tint = specularFactor F0c / max3(F0c).
// At normal incidence the coat reflects glTF's specularFactor F0c exactly;
// at grazing angles it reflects specularFactor for a grey specular colour
// (glTF's f90), less for a coloured one (each channel's share of the
// largest). The base is weighted by the untinted Fresnel term, as glTF's
// max3(F), except that a specularFactor below 1 does not lighten it.
//
// KHR_materials_clearcoat puts a second coat over all of that (F0 0.04, its
// own roughness) of strength clearcoatFactor c. Ferry has one coat: its
// tint, eta and roughness are the specular layer's and the clear coat's
// (tint 1, eta 1.5) mixed by c: the specular layer alone at c = 0, the clear
// coat alone at c = 1 (the specular layer under it dropped), one lobe of
// intermediate roughness and strength in between.
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
