// A conductor (metal): reflectance `color` at normal incidence with
// Schlick's Fresnel; a mirror below GGX width 1e-3, else a GGX lobe sampled
// by visible normals.
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

// `roughness`: Ferry's (GGX alpha = roughness^2).
Bsdf conductorBsdf(Vec3f f0, float roughness);

struct ConductorModel final : MaterialModel {
  float roughness = 0;

  ConductorModel() = default;
  explicit ConductorModel(float roughness) : roughness(roughness) {}
  std::string_view name() const override { return "conductor"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override {
    return conductorBsdf(color, roughness);
  }
  void write(MaterialRecordWriter& record) const override { record.pod(roughness); }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
