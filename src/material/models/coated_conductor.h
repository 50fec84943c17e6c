// A GGX conductor (reflectance: the colour) under a layered dielectric coat
// (pbrt-v4's coatedconductor, approximated: the base times (1 - F) in and
// out, plus the coat; material/models/coated_diffuse.h's CoatLobe).
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

Bsdf coatedConductorBsdf(Vec3f f0, float baseRoughness, Vec3f specular, float roughness, float eta);

struct CoatedConductorModel final : MaterialModel {
  float baseRoughness = 0;  // the conductor's, Ferry's (GGX alpha = roughness^2)
  Vec3f specular{1};        // the coat's tint; black: no coat (a bare conductor)
  float roughness = 0;      // the coat's
  float eta = 1.5f;         // the coat's relative index of refraction

  std::string_view name() const override { return "coated-conductor"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override;
  void write(MaterialRecordWriter& record) const override;
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
