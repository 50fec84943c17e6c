// A dielectric interface (glass, water): Fresnel reflection and refraction
// with index of refraction `ior` (inside over outside), the transmitted light
// tinted by the colour; smooth below GGX width 1e-3, else rough (GGX, Walter
// et al. 2007). The transmitted radiance is not scaled by 1/eta^2: the
// factors cancel for closed objects, and without them a white BSDF never
// returns more than it receives, which the energy tests check.
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

// `roughness`: Ferry's (GGX alpha = roughness^2); an ior <= 0 is 1.5.
Bsdf dielectricBsdf(float ior, float roughness, Vec3f tint = Vec3f(1));

struct DielectricModel final : MaterialModel {
  float ior = 1.5f;
  float roughness = 0;

  DielectricModel() = default;
  DielectricModel(float ior, float roughness) : ior(ior), roughness(roughness) {}
  std::string_view name() const override { return "dielectric"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override {
    return dielectricBsdf(ior, roughness, color);
  }
  void write(MaterialRecordWriter& record) const override {
    record.pod(ior);
    record.pod(roughness);
  }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
