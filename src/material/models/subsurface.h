// Subsurface scattering (pbrt's "subsurface" and "kdsubsurface"), as a
// random walk: the surface is pbrt's dielectric interface from outside
// (reflection tinted by Kr, transmission by Kt), and light that enters walks
// through the medium inside (a homogeneous medium of the scene that the
// loader puts behind the surface: scene/scene.h, Medium::subsurface). A walk
// that comes back to the surface leaves by pbrt's exit lobe Sw (a
// Fresnel-weighted cosine) with probability 1 - F of its angle inside, and
// is reflected back in otherwise. docs/path-tracer.md, "Subsurface".
#pragma once

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

struct SubsurfaceModel final : MaterialModel {
  float ior = 1.33f;
  float roughness = 0;   // Ferry's: GGX alpha = roughness^2
  Vec3f reflectTint{1};  // pbrt-v3's Kr (transmission is tinted by the base colour, Kt)

  SubsurfaceModel() = default;
  SubsurfaceModel(float ior, float roughness, Vec3f reflectTint);
  std::string_view name() const override { return "subsurface"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override;
  void write(MaterialRecordWriter& record) const override;
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;

 private:
  float exitNormalization_ = 1;  // c = 1 - 2 FM1: Sw's cosine integral is 1
};

// The exit lobe's normalization for index `ior`: the cosine-weighted mean
// over the hemisphere of 1 - F(cos, ior).
float subsurfaceExitNormalization(float ior);

// pbrt's inversion of a diffuse reflectance (kdsubsurface's Kd, pbrt-v4's
// reflectance) into a single-scattering albedo, through the photon beam
// diffusion profile (Habel et al. 2013) with asymmetry `g` and index `eta`:
// the albedo whose profile integrates to `reflectance`, per channel.
Vec3f subsurfaceAlbedoFromReflectance(Vec3f reflectance, float g, float eta);
// The photon beam diffusion profile's integral for single-scattering
// albedo `albedo` (extinction 1): the effective albedo pbrt tabulates.
float photonBeamDiffusionReflectance(float albedo, float g, float eta);

}  // namespace ferry
