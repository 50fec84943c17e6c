// Scattering at a surface point, in the local shading frame (normal = +z).
// Directions point away from the surface: wo towards where the path came
// from, wi towards where it goes next.
//
// A Material maps to one of seven kinds (see Bsdf::fromMaterial): diffuse
// (Lambertian, or Oren-Nayar with pbrt's sigma), smooth or rough (GGX)
// conductor, smooth or rough (GGX, Walter et al. 2007) dielectric, a
// diffuse base under a rough dielectric coat (pbrt's plastic: base + coat, or
// the base seen through the coat), and pbrt-v3's tabulated Fourier BSDF
// (render/fourier_bsdf.h). Rough lobes are sampled with Heitz's
// visible-normal distribution. The dielectrics' transmitted radiance is not
// scaled by 1/eta^2: the factors cancel for closed objects, and without them a
// white BSDF never returns more than it receives, which the energy tests
// check. (The Fourier BSDF scales it as pbrt-v3 does: its tables are pbrt's.)
#pragma once

#include "core/math.h"

namespace ferry {

struct Material;
struct FourierBsdfTable;

struct BsdfSample {
  Vec3f wi;
  Vec3f weight;   // f * |cos(wi)| / pdf
  float pdf = 0;  // solid angle; meaningless for delta lobes
  bool delta = false;
};

class Bsdf {
 public:
  enum class Kind {
    Diffuse,
    SmoothConductor,
    RoughConductor,
    SmoothDielectric,
    RoughDielectric,
    Coated,
    Fourier,
    DiffuseTransmission
  };

  // `color` is the material's base colour times its texture at the hit;
  // `table` the scene's table the material names (Material::bsdfTable), or
  // null.
  static Bsdf fromMaterial(const Material& material, Vec3f color,
                           const FourierBsdfTable* table = nullptr);
  // pbrt-v3's FourierBSDF over `table` (which must outlive the Bsdf).
  static Bsdf fourier(const FourierBsdfTable& table);
  // `sigmaDegrees`: Oren-Nayar roughness (pbrt-v3's OrenNayar; 0: Lambertian).
  static Bsdf diffuse(Vec3f albedo, float sigmaDegrees = 0);
  // A diffuse base (`base`, Oren-Nayar `sigmaDegrees`) under a GGX coat of
  // tint `specular`, Ferry roughness `roughness` and Fresnel term
  // fresnelDielectric(cos, eta) at the microfacet. `layered` false: f = base
  // + coat (pbrt-v3's plastic, which can reflect more than it receives);
  // true: the base times (1 - F(wo)) (1 - F(wi)), light refracted into and
  // out of the coat, plus the coat (energy conserving, reciprocal). The coat
  // is never delta: its alpha is at least 2e-3.
  static Bsdf coated(Vec3f base, Vec3f specular, float roughness, float eta, bool layered,
                     float sigmaDegrees = 0);
  // pbrt-v3's FresnelBlend (Ashikhmin and Shirley 2000, its "substrate"):
  // base `rd` and a GGX coat whose Schlick Fresnel reflects `rs` at normal
  // incidence; the base fades where the coat reflects more.
  static Bsdf fresnelBlend(Vec3f rd, Vec3f rs, float roughness);
  // A GGX conductor (reflectance `f0` at normal incidence, Ferry roughness
  // `baseRoughness`) under a layered dielectric coat as coated()'s (pbrt-v4's
  // coatedconductor, approximated: the base times (1 - F) in and out).
  static Bsdf coatedConductor(Vec3f f0, float baseRoughness, Vec3f specular, float roughness,
                              float eta);
  // A thin diffuse sheet (pbrt-v4's DiffuseTransmissionBxDF): Lambertian
  // reflection of `reflectance` on the side light arrives from, Lambertian
  // transmission of `transmittance` to the other; sampled by the two
  // albedos' largest channels, as pbrt-v4.
  static Bsdf diffuseTransmission(Vec3f reflectance, Vec3f transmittance);
  static Bsdf conductor(Vec3f f0, float roughness);
  static Bsdf dielectric(float ior, float roughness, Vec3f tint = Vec3f(1));

  Kind kind() const { return kind_; }
  bool isDelta() const { return kind_ == Kind::SmoothConductor || kind_ == Kind::SmoothDielectric; }
  // Transmitting BSDFs keep their normals (the sign of wo.z says the side);
  // the others are shaded on the side the ray arrived from.
  bool transmits() const {
    return kind_ == Kind::SmoothDielectric || kind_ == Kind::RoughDielectric ||
           kind_ == Kind::DiffuseTransmission || (kind_ == Kind::Fourier && tableTransmits_);
  }

  // f(wo, wi) * |cos(wi)|; zero for delta lobes.
  Vec3f eval(Vec3f wo, Vec3f wi) const;
  // Solid-angle density with which sample() picks wi; zero for delta lobes.
  float pdf(Vec3f wo, Vec3f wi) const;
  // Draws wi from (uLobe, u); false when no direction is produced.
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const;

  float alpha() const { return alpha_; }

 private:
  Vec3f diffuseEval(Vec3f wo, Vec3f wi) const;
  Vec3f coatEval(Vec3f wo, Vec3f wi) const;
  float coatPdf(Vec3f wo, Vec3f wi) const;

  Kind kind_ = Kind::Diffuse;
  Vec3f color_{0.8f};
  float alpha_ = 1;  // GGX width (roughness^2)
  float ior_ = 1.5f;
  // Oren-Nayar's A and B (Lambertian: 1 and 0).
  float orenA_ = 1, orenB_ = 0;
  // Coated: the coat's tint, whether the base is seen through it, and the
  // probability of sampling the coat rather than the base.
  Vec3f specular_{0};  // Coated: the coat's tint; DiffuseTransmission: the transmittance
  bool layered_ = false;
  bool fresnelBlend_ = false;
  float baseAlpha_ = 0;  // Coated: > 0 for a conductor base (its GGX alpha), 0 for diffuse
  float coatProbability_ = 0;
  // Fourier: the scene's table.
  const FourierBsdfTable* table_ = nullptr;
  bool tableTransmits_ = false;
};

// Helpers exposed for tests.
float fresnelDielectric(float cosThetaI, float eta);  // eta = n_transmitted / n_incident
// A cosine-weighted direction about +z (inline: every diffuse bounce and
// constant-sky light sample takes one).
[[gnu::always_inline]] inline Vec3f sampleCosineHemisphere(Vec2f u) {
  float r = std::sqrt(u.x);
  float sinPhi, cosPhi;
  sinCosTwoPi(u.y, sinPhi, cosPhi);
  return {r * cosPhi, r * sinPhi, std::sqrt(std::max(0.0f, 1 - u.x))};
}

}  // namespace ferry
