// A thin diffuse sheet (pbrt-v4's diffusetransmission, pbrt-v3's
// translucent without its glossy part): Lambertian reflection of the colour
// on the side light arrives from, Lambertian transmission of
// `transmittance` to the other; sampled by the two albedos' largest
// channels, as pbrt-v4.
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

Bsdf diffuseTransmissionBsdf(Vec3f reflectance, Vec3f transmittance);

struct DiffuseTransmissionModel final : MaterialModel {
  Vec3f transmittance{0.25f};  // black: opaque (Lambertian)

  DiffuseTransmissionModel() = default;
  explicit DiffuseTransmissionModel(Vec3f t) : transmittance(t) {}
  std::string_view name() const override { return "diffuse-transmission"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override;
  void write(MaterialRecordWriter& record) const override { record.pod(transmittance); }
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
