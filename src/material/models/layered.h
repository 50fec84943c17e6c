// pbrt-v4's layered BSDF (coateddiffuse, coatedconductor): a dielectric
// interface (index `eta`, GGX width `alpha`, smooth below 1e-3) over an
// opaque base (Lambertian of reflectance `base`, or a GGX conductor of
// Schlick reflectance `base` and width `baseAlpha`), with a slab of
// `thickness` between them that attenuates by exp(-thickness / |cos|) and,
// with a non-black `albedo`, scatters by Henyey-Greenstein `g`. Light is
// followed between the layers by a random walk of at most `maxDepth`
// scattering events (Guo, Hasan, Zhao 2018, with pbrt-v4's estimators).
//
// eval() and pdf() are unbiased estimates (pbrt-v4's `nsamples` walks), not
// closed forms: their random numbers are a hash of the directions (and of the
// sample's own numbers for sample()), so one (wo, wi) always gets one value
// and images do not depend on ranks, threads or order. sample() returns the
// walk's own weight and, for MIS, pdf()'s estimate of its direction.
#pragma once

#include <cstdint>

#include "material/bsdf.h"
#include "material/material_model.h"

namespace ferry {

struct LayeredLobe {
  Vec3f base{0.5f};      // the diffuse base's reflectance, or the conductor's F0
  float baseAlpha = -1;  // the conductor base's GGX width; negative: a diffuse base
  float eta = 1.5f;      // the interface's relative index (inside over outside)
  float alpha = 0;       // the interface's GGX width (pbrt-v4's alpha)
  float thickness = 0.01f;
  Vec3f albedo{0};  // the slab's single-scattering albedo
  float g = 0;      // the slab's Henyey-Greenstein asymmetry
  uint16_t maxDepth = 10;
  uint16_t samples = 1;  // walks per eval() and pdf()

  Vec3f eval(Vec3f wo, Vec3f wi) const;  // f(wo, wi) |cos(wi)|
  float pdf(Vec3f wo, Vec3f wi) const;
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const;
};

Bsdf layeredBsdf(const LayeredLobe& lobe);

// The model: the material's colour is the base's reflectance (diffuse) or
// F0 (conductor). Widths are GGX alphas (pbrt-v4's, after its remapping).
struct LayeredModel final : MaterialModel {
  bool conductorBase = false;
  float baseAlpha = 0;  // the conductor base's
  float eta = 1.5f;
  float alpha = 0;  // the interface's
  float thickness = 0.01f;
  Vec3f albedo{0};
  float g = 0;
  int maxDepth = 10;
  int samples = 1;

  std::string_view name() const override { return "layered"; }
  Bsdf bsdf(Vec3f color, const MaterialResources&) const override;
  void write(MaterialRecordWriter& record) const override;
  static std::shared_ptr<const MaterialModel> read(MaterialRecordReader& record);
  std::string describe() const override;
};

}  // namespace ferry
