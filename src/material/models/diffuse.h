// Diffuse reflection: Lambertian, or Oren-Nayar with pbrt's "sigma" (the
// microfacet slope's standard deviation in degrees; pbrt's matte).
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

// Lambertian reflection of `color` times Oren-Nayar's factor (A and B:
// 1 and 0 for Lambertian).
struct DiffuseLobe {
  Vec3f color;
  float orenA = 1, orenB = 0;

  DiffuseLobe(Vec3f albedo, float sigmaDegrees);
  Vec3f eval(Vec3f wo, Vec3f wi) const;
  float pdf(Vec3f wo, Vec3f wi) const;
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const;
};

// `sigmaDegrees`: Oren-Nayar roughness (pbrt-v3's OrenNayar; 0: Lambertian).
Bsdf diffuseBsdf(Vec3f albedo, float sigmaDegrees = 0);

struct DiffuseModel final : MaterialModel {
  float sigmaDegrees = 0;  // in [0, 90]

  DiffuseModel() = default;
  explicit DiffuseModel(float sigmaDegrees) : sigmaDegrees(sigmaDegrees) {}
  std::string_view name() const override { return "diffuse"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override {
    return diffuseBsdf(color, sigmaDegrees);
  }
  void write(MaterialRecordWriter& record) const override { record.pod(sigmaDegrees); }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
