// A thin dielectric sheet (pbrt-v4's thindielectric: a window pane, a soap
// film): light reflects as a mirror with the reflectance of the sheet's two
// faces and all the bounces between them, R' = R + T^2 R / (1 - R^2) with
// R = F(cos, ior), T = 1 - R, and passes the rest straight through,
// unrefracted, tinted by the colour.
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

Bsdf thinDielectricBsdf(float ior, Vec3f tint = Vec3f(1));

struct ThinDielectricModel final : MaterialModel {
  float ior = 1.5f;

  ThinDielectricModel() = default;
  explicit ThinDielectricModel(float ior) : ior(ior) {}
  std::string_view name() const override { return "thin-dielectric"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override {
    return thinDielectricBsdf(ior, color);
  }
  void write(MaterialRecordWriter& record) const override { record.pod(ior); }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
