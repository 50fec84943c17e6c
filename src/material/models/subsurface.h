// Subsurface scattering (pbrt's "subsurface" and "kdsubsurface"). The
// surface is pbrt's dielectric interface from outside (reflection tinted by
// Kr, transmission by Kt). Light that enters leaves in one of two ways
// (docs/path-tracer.md, "Subsurface"):
//   probes  pbrt's tabulated BSSRDF: the exit point is found by a probe
//           segment (SubsurfaceProfile, sampleProbeSegment) and leaves by
//           pbrt's exit lobe Sw (SubsurfaceExitLobe);
//   walks   a random walk through the medium inside (a homogeneous medium of
//           the scene that the loader puts behind the surface: scene/scene.h,
//           Medium::subsurface); back at the surface it leaves by Sw with
//           probability 1 - F of its angle inside, else is reflected back in.
#pragma once

#include <memory>
#include <vector>

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

// pbrt's photon beam diffusion profile tabulated for asymmetry g and index
// eta at extinction 1 (its ComputeBeamDiffusionBSSRDF): 2 pi r S(r) at
// kAlbedos single-scattering albedos by kRadii optical radii, each row's
// cdf over the radius, and its integral (the effective albedo).
struct BssrdfTable {
  static constexpr int32_t kAlbedos = 100, kRadii = 64;
  float g = 0, eta = 1;
  std::vector<float> albedo, radius, profile, cdf, effectiveAlbedo;
};
// Made once per (g, eta) and shared.
std::shared_ptr<const BssrdfTable> beamDiffusionTable(float g, float eta);

// A material's BSSRDF over the table (pbrt's TabulatedBSSRDF): its
// extinction and single-scattering albedo per channel.
struct SubsurfaceProfile {
  Vec3f sigmaT{0}, albedo{0};
  const BssrdfTable* table = nullptr;

  // The radial profile Sr at distance r, per channel.
  Vec3f sr(float r) const;
  // A distance drawn from channel ch's profile (negative: none).
  float sampleSr(int ch, float u) const;
  // The density of sampleSr(ch, .) at r, over the plane (per unit area).
  float pdfSr(int ch, float r) const;
};

// pbrt's probe: a chord of the sphere about the entry point that holds the
// profile (its radius: channel ch's 0.999 quantile), along one axis of the
// entry's frame (its normal with probability 1/2, each tangent 1/4), at a
// distance drawn from the profile. Every surface of the material the chord
// crosses is a candidate exit point. False when the draw gives none.
struct ProbeSegment {
  Vec3f start, end;
};
bool sampleProbeSegment(const SubsurfaceProfile& profile, Vec3f entry, const Frame& frame,
                        float uAxis, Vec2f u, ProbeSegment& out);
// The density with which probes find exit point `exit` (geometric normal
// `exitNormal`), per unit area, over all three axes and channels (pbrt's
// Pdf_Sp; a probe that found n candidates divides it by n).
float probeDensity(const SubsurfaceProfile& profile, Vec3f entry, const Frame& frame, Vec3f exit,
                   Vec3f exitNormal);

// pbrt's exit lobe Sw: light leaves the surface by (1 - F(cos, eta)) / (c pi)
// over the hemisphere of the shading normal (c: subsurfaceExitNormalization,
// so that it integrates to 1 against the cosine), whatever wo.
struct SubsurfaceExitLobe {
  float ior = 1.33f, exitNormalization = 1;
  Vec3f eval(Vec3f wo, Vec3f wi) const;
  float pdf(Vec3f wo, Vec3f wi) const;
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const;
};

struct SubsurfaceModel final : MaterialModel {
  float ior = 1.33f;
  float roughness = 0;   // Ferry's: GGX alpha = roughness^2
  Vec3f reflectTint{1};  // pbrt-v3's Kr (transmission is tinted by the base colour, Kt)

  // The medium inside (sigma_a, sigma_s already scaled, g): what the BSSRDF
  // is made from (part files of format 14 and older have none: those are
  // walked). The loader gives the walks the same medium.
  bool hasMedium = false;
  Vec3f sigmaA{0}, sigmaS{0};
  float g = 0;
  // Which material a probe counts: surfaces whose model has the probe id of
  // the one light entered (pbrt: the same material object). The same on
  // every rank and in part files.
  uint32_t probeId = 0;

  SubsurfaceModel() = default;
  SubsurfaceModel(float ior, float roughness, Vec3f reflectTint);
  SubsurfaceModel(float ior, float roughness, Vec3f reflectTint, Vec3f sigmaA, Vec3f sigmaS,
                  float g, uint32_t probeId);
  std::string_view name() const override { return "subsurface"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override;
  void write(MaterialRecordWriter& record) const override;
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
  // The BSSRDF (hasMedium only).
  SubsurfaceProfile profile() const;
  SubsurfaceExitLobe exitLobe() const { return {ior, exitNormalization_}; }
  // The surface under probes: the dielectric interface from either side
  // (bsdf() is the walks', whose inside is the exit lobe).
  Bsdf probedBsdf(Vec3f color) const;

 private:
  float exitNormalization_ = 1;  // c = 1 - 2 FM1: Sw's cosine integral is 1
  std::shared_ptr<const BssrdfTable> table_;
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
