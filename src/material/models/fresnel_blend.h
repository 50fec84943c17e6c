// pbrt-v3's substrate: FresnelBlend (Ashikhmin and Shirley 2000), a diffuse
// base (the colour) and a GGX coat whose Schlick Fresnel reflects `specular`
// at normal incidence; the base fades where the coat reflects more.
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

Bsdf fresnelBlendBsdf(Vec3f rd, Vec3f rs, float roughness);

struct FresnelBlendModel final : MaterialModel {
  Vec3f specular{0.5f};    // black: no coat (Lambertian)
  float roughness = 0.3f;  // the coat's, Ferry's (GGX alpha = roughness^2)

  std::string_view name() const override { return "fresnel-blend"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override;
  void write(MaterialRecordWriter& record) const override {
    record.pod(specular);
    record.pod(roughness);
  }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
