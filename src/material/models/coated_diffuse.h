// A diffuse base under a glossy dielectric coat: pbrt-v3's plastic (base +
// coat, which can reflect more than it receives), or the base seen through
// the coat, times (1 - F) on the way in and out (pbrt-v4's coateddiffuse,
// approximated: energy conserving and reciprocal). The coat is a GGX lobe of
// tint `specular` with Fresnel term fresnelDielectric(cos, eta) at the
// microfacet; it is never delta (its alpha is at least 2e-3). CoatLobe is
// shared by the coated conductor and FresnelBlend.
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"
#include "material/models/diffuse.h"

namespace ferry {

struct CoatLobe {
  DiffuseLobe base;           // the diffuse base (unused over a conductor)
  Vec3f specular{0};          // the coat's tint
  float alpha = 1;            // the coat's GGX width
  float ior = 1.5f;           // the coat's relative index
  float baseAlpha = 0;        // > 0: a GGX conductor base of this width and reflectance base.color
  float coatProbability = 0;  // of sampling the coat rather than the base
  bool layered = false;       // the base seen through the coat
  bool fresnelBlend = false;  // pbrt-v3's FresnelBlend (material/models/fresnel_blend.h)

  // A diffuse base `base` (Oren-Nayar `sigmaDegrees`) under the coat.
  CoatLobe(Vec3f base, Vec3f specular, float roughness, float eta, bool layered,
           float sigmaDegrees);
  Vec3f eval(Vec3f wo, Vec3f wi) const;
  float pdf(Vec3f wo, Vec3f wi) const;
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const;
};

Bsdf coatedBsdf(Vec3f base, Vec3f specular, float roughness, float eta, bool layered,
                float sigmaDegrees = 0);

struct CoatedDiffuseModel final : MaterialModel {
  Vec3f specular{0};       // the coat's tint; black: no coat (diffuse)
  float roughness = 0.3f;  // the coat's, Ferry's (GGX alpha = roughness^2)
  float eta = 1.5f;        // the coat's relative index of refraction
  bool layered = false;    // false: base + coat (pbrt-v3 plastic)
  float sigmaDegrees = 0;  // the base's Oren-Nayar roughness

  std::string_view name() const override { return "coated-diffuse"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override;
  void write(MaterialRecordWriter& record) const override;
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
