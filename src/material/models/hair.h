// Hair (pbrt's "hair": Chiang et al. 2016 as pbrt-v3 implements it): a
// rough dielectric cylinder whose R, TT, TRT and remaining lobes are
// longitudinal (Mp), attenuation (Ap) and azimuthal (Np) terms. The shading
// frame's s axis runs along the fibre and the hit's v across it (h = 2v - 1,
// where the ray meets the cylinder); the fibre absorbs by sigma_a, given
// directly, from melanin concentrations, or from a colour (the material's
// base colour) that the fibre's multiple scattering reproduces.
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

struct HairModel final : MaterialModel {
  enum class Absorption : uint8_t { SigmaA = 0, Melanin = 1, Color = 2 };
  Absorption absorption = Absorption::Melanin;
  Vec3f sigmaA{0};                          // Absorption::SigmaA
  float eumelanin = 1.3f, pheomelanin = 0;  // Absorption::Melanin
  float eta = 1.55f;                        // index of refraction of the fibre
  float betaM = 0.3f, betaN = 0.3f;         // longitudinal and azimuthal roughness, [0, 1]
  float alphaDegrees = 2;                   // the scales' tilt

  std::string_view name() const override { return "hair"; }
  // Across the fibre at h = 0 (no hit point known).
  Bsdf bsdf(Vec3f color, const MaterialResources& resources) const override;
  Bsdf bsdfAt(Vec3f color, Vec2f uv, const MaterialResources& resources) const override;
  void write(MaterialRecordWriter& record) const override;
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
  // The absorption coefficient at a point whose base colour is `color`.
  Vec3f absorptionAt(Vec3f color) const;
};

// pbrt's conversions: melanin concentrations to sigma_a, and a colour to the
// sigma_a whose multiple scattering gives it (for azimuthal roughness betaN).
Vec3f hairSigmaAFromMelanin(float eumelanin, float pheomelanin);
Vec3f hairSigmaAFromColor(Vec3f color, float betaN);
// The hair BSDF at offset h in [-1, 1] across the fibre.
Bsdf hairBsdf(float h, float eta, Vec3f sigmaA, float betaM, float betaN, float alphaDegrees);

}  // namespace ferry
