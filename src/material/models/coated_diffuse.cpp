#include "material/models/coated_diffuse.h"

#include <fmt/format.h>

#include "material/microfacet.h"

namespace ferry {

using namespace microfacet;

CoatLobe::CoatLobe(Vec3f baseColor, Vec3f tint, float roughness, float eta, bool isLayered,
                   float sigmaDegrees)
    : base(baseColor, sigmaDegrees),
      specular(max(tint, Vec3f(0))),
      alpha(std::max(roughness * roughness, 2e-3f)),
      ior(eta > 0 ? eta : 1.5f),
      layered(isLayered) {
  // Sample the coat in proportion to its tint against the base's colour (the
  // Fresnel term is not known before wo meets a microfacet); never all one
  // side unless the other is black, so that MIS and pdf() see both.
  const float coat = luminance(specular), diffuseWeight = luminance(max(baseColor, Vec3f(0)));
  coatProbability = coat <= 0            ? 0
                    : diffuseWeight <= 0 ? 1
                                         : std::clamp(coat / (coat + diffuseWeight), 0.1f, 0.9f);
}

Vec3f CoatLobe::eval(Vec3f wo, Vec3f wi) const {
  if (wo.z <= 0 || wi.z <= 0) return Vec3f(0);
  if (fresnelBlend) {
    // pbrt-v3's FresnelBlend::f, times cos(wi).
    auto pow5 = [](float v) { return (v * v) * (v * v) * v; };
    const Vec3f diffuse =
        base.color * (Vec3f(1) - specular) *
        (28 / (23 * kPi) * (1 - pow5(1 - 0.5f * wi.z)) * (1 - pow5(1 - 0.5f * wo.z)));
    const Vec3f m = normalize(wo + wi);
    const float cosIM = dot(wi, m);
    if (!(cosIM > 0)) return diffuse * wi.z;
    const Vec3f schlickF = specular + (Vec3f(1) - specular) * pow5(1 - cosIM);
    return diffuse * wi.z + schlickF * (ggxD(m, alpha) / (4 * cosIM * std::max(wi.z, wo.z)) * wi.z);
  }
  Vec3f under =
      baseAlpha > 0 ? roughConductorEval(wo, wi, base.color, baseAlpha) : base.eval(wo, wi);
  if (layered)
    under = under * ((1 - fresnelDielectric(wo.z, ior)) * (1 - fresnelDielectric(wi.z, ior)));
  const Vec3f m = normalize(wo + wi);
  // pbrt's MicrofacetReflection: F at the microfacet, cos(wi, m).
  const float f = fresnelDielectric(dot(wi, m), ior);
  return under + specular * (f * ggxD(m, alpha) * ggxG2(wo, wi, alpha) / (4 * wo.z));
}

float CoatLobe::pdf(Vec3f wo, Vec3f wi) const {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  const Vec3f m = normalize(wo + wi);
  const float cosOM = dot(wo, m);
  const float glossy = cosOM > 0 ? visibleNormalPdf(wo, m, alpha) / (4 * cosOM) : 0;
  const float under = baseAlpha > 0 ? roughConductorPdf(wo, wi, baseAlpha) : wi.z / kPi;
  return coatProbability * glossy + (1 - coatProbability) * under;
}

bool CoatLobe::sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
  if (wo.z <= 0) return false;
  if (uLobe < coatProbability || baseAlpha > 0) {
    // The coat's microfacets, or the conductor base's.
    const float a = uLobe < coatProbability ? alpha : baseAlpha;
    out.wi = reflect(wo, sampleVisibleNormal(wo, a, u));
  } else {
    out.wi = sampleCosineHemisphere(u);
  }
  if (out.wi.z <= 0) return false;
  out.pdf = pdf(wo, out.wi);
  if (!(out.pdf > 0)) return false;
  out.weight = eval(wo, out.wi) * (1 / out.pdf);
  out.delta = false;
  return true;
}

Bsdf coatedBsdf(Vec3f base, Vec3f specular, float roughness, float eta, bool layered,
                float sigmaDegrees) {
  return Bsdf(CoatLobe(base, specular, roughness, eta, layered, sigmaDegrees), false, false);
}

Bsdf CoatedDiffuseModel::bsdf(Vec3f color, const MaterialResources&) const {
  if (!(maxComponent(specular) > 0)) return diffuseBsdf(color, sigmaDegrees);
  return coatedBsdf(color, specular, roughness, eta, layered, sigmaDegrees);
}

void CoatedDiffuseModel::write(MaterialRecordWriter& record) const {
  record.pod(specular);
  record.pod(roughness);
  record.pod(eta);
  record.pod(uint8_t(layered));
  record.pod(sigmaDegrees);
}

std::shared_ptr<const MaterialModel> CoatedDiffuseModel::read(MaterialRecordReader& record) {
  auto m = std::make_shared<CoatedDiffuseModel>();
  m->specular = record.color();
  m->roughness = record.number();
  m->eta = record.number();
  const uint8_t layered = record.pod<uint8_t>();
  if (layered > 1) record.fail(fmt::format("layered is {}, not 0 or 1", layered));
  m->layered = layered == 1;
  m->sigmaDegrees = record.number();
  return m;
}

std::string CoatedDiffuseModel::describe() const {
  return fmt::format("coated diffuse ({}, coat ({:g}, {:g}, {:g}), roughness {:g}, eta {:g})",
                     layered ? "layered" : "additive", specular.x, specular.y, specular.z,
                     roughness, eta);
}

}  // namespace ferry
