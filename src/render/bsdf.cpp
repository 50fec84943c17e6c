#include "render/bsdf.h"

#include <cmath>

#include "render/fourier_bsdf.h"
#include "scene/scene.h"

namespace ferry {
namespace {

// Below this GGX width the lobe is treated as a perfect mirror / window.
constexpr float kSmoothAlpha = 1e-3f;

float ggxD(Vec3f m, float alpha) {
  if (m.z <= 0) return 0;
  float a2 = alpha * alpha;
  float c2 = m.z * m.z;
  float d = c2 * (a2 - 1) + 1;
  return a2 / (kPi * d * d);
}

float ggxLambda(Vec3f w, float alpha) {
  float c2 = w.z * w.z;
  if (c2 >= 1) return 0;
  float tan2 = (1 - c2) / std::max(c2, 1e-12f);
  return 0.5f * (-1 + std::sqrt(1 + alpha * alpha * tan2));
}

float ggxG1(Vec3f w, float alpha) {
  return 1 / (1 + ggxLambda(w, alpha));
}
float ggxG2(Vec3f wo, Vec3f wi, float alpha) {
  return 1 / (1 + ggxLambda(wo, alpha) + ggxLambda(wi, alpha));
}

// Density of visible normals seen from wo (wo.z > 0).
float visibleNormalPdf(Vec3f wo, Vec3f m, float alpha) {
  float cosOM = dot(wo, m);
  if (cosOM <= 0 || wo.z <= 0) return 0;
  return ggxG1(wo, alpha) * cosOM * ggxD(m, alpha) / wo.z;
}

// Heitz 2018, "Sampling the GGX Distribution of Visible Normals".
Vec3f sampleVisibleNormal(Vec3f wo, float alpha, Vec2f u) {
  Vec3f vh = normalize(Vec3f(alpha * wo.x, alpha * wo.y, wo.z));
  float lensq = vh.x * vh.x + vh.y * vh.y;
  Vec3f t1 = lensq > 0 ? Vec3f(-vh.y, vh.x, 0) * (1 / std::sqrt(lensq)) : Vec3f(1, 0, 0);
  Vec3f t2 = cross(vh, t1);
  float r = std::sqrt(u.x);
  float sinPhi, cosPhi;
  sinCosTwoPi(u.y, sinPhi, cosPhi);
  float p1 = r * cosPhi;
  float p2 = r * sinPhi;
  float s = 0.5f * (1 + vh.z);
  p2 = (1 - s) * std::sqrt(std::max(0.0f, 1 - p1 * p1)) + s * p2;
  Vec3f nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0f, 1 - p1 * p1 - p2 * p2));
  return normalize(Vec3f(alpha * nh.x, alpha * nh.y, std::max(1e-7f, nh.z)));
}

Vec3f reflect(Vec3f wo, Vec3f m) {
  return m * (2 * dot(wo, m)) - wo;
}

// Refracts wo (on the side m points to) through the interface; eta = n_t / n_i.
bool refract(Vec3f wo, Vec3f m, float eta, Vec3f& wi) {
  float cosI = dot(wo, m);
  float sin2T = (1 - cosI * cosI) / (eta * eta);
  if (sin2T >= 1) return false;
  float cosT = std::sqrt(1 - sin2T);
  wi = -wo * (1 / eta) + m * (cosI / eta - cosT);
  return true;
}

// A GGX conductor's f * cos(wi) and sampling density (visible normals).
Vec3f schlick(Vec3f f0, float cosTheta);
Vec3f roughConductorEval(Vec3f wo, Vec3f wi, Vec3f f0, float alpha) {
  if (wo.z <= 0 || wi.z <= 0) return Vec3f(0);
  const Vec3f m = normalize(wo + wi);
  return schlick(f0, dot(wo, m)) * (ggxD(m, alpha) * ggxG2(wo, wi, alpha) / (4 * wo.z));
}
float roughConductorPdf(Vec3f wo, Vec3f wi, float alpha) {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  const Vec3f m = normalize(wo + wi);
  const float cosOM = dot(wo, m);
  return cosOM > 0 ? visibleNormalPdf(wo, m, alpha) / (4 * cosOM) : 0;
}

Vec3f schlick(Vec3f f0, float cosTheta) {
  float c = std::clamp(1 - cosTheta, 0.0f, 1.0f);
  float c5 = c * c * c * c * c;
  return f0 + (Vec3f(1) - f0) * c5;
}

}  // namespace

float fresnelDielectric(float cosI, float eta) {
  cosI = std::clamp(cosI, 0.0f, 1.0f);
  float sin2T = (1 - cosI * cosI) / (eta * eta);
  if (sin2T >= 1) return 1;
  float cosT = std::sqrt(1 - sin2T);
  float rs = (cosI - eta * cosT) / (cosI + eta * cosT);
  float rp = (eta * cosI - cosT) / (eta * cosI + cosT);
  return 0.5f * (rs * rs + rp * rp);
}

Bsdf Bsdf::diffuse(Vec3f albedo, float sigmaDegrees) {
  Bsdf b;
  b.kind_ = Kind::Diffuse;
  b.color_ = albedo;
  if (sigmaDegrees > 0) {
    // pbrt-v3's OrenNayar constructor.
    const float sigma = sigmaDegrees * (kPi / 180), sigma2 = sigma * sigma;
    b.orenA_ = 1 - sigma2 / (2 * (sigma2 + 0.33f));
    b.orenB_ = 0.45f * sigma2 / (sigma2 + 0.09f);
  }
  return b;
}

Bsdf Bsdf::coated(Vec3f base, Vec3f specular, float roughness, float eta, bool layered,
                  float sigmaDegrees) {
  Bsdf b = diffuse(base, sigmaDegrees);
  b.kind_ = Kind::Coated;
  b.specular_ = max(specular, Vec3f(0));
  b.alpha_ = std::max(roughness * roughness, 2e-3f);
  b.ior_ = eta > 0 ? eta : 1.5f;
  b.layered_ = layered;
  // Sample the coat in proportion to its tint against the base's colour (the
  // Fresnel term is not known before wo meets a microfacet); never all one
  // side unless the other is black, so that MIS and pdf() see both.
  const float coat = luminance(b.specular_), diffuseWeight = luminance(max(base, Vec3f(0)));
  b.coatProbability_ = coat <= 0            ? 0
                       : diffuseWeight <= 0 ? 1
                                            : std::clamp(coat / (coat + diffuseWeight), 0.1f, 0.9f);
  return b;
}

Bsdf Bsdf::coatedConductor(Vec3f f0, float baseRoughness, Vec3f specular, float roughness,
                           float eta) {
  Bsdf b = coated(f0, specular, roughness, eta, true);
  b.baseAlpha_ = std::max(baseRoughness * baseRoughness, 2e-3f);
  return b;
}

Bsdf Bsdf::fresnelBlend(Vec3f rd, Vec3f rs, float roughness) {
  Bsdf b = coated(rd, rs, roughness, 1.5f, false);
  b.fresnelBlend_ = true;
  return b;
}

// f * cos(wi) of the diffuse base: Lambertian, or Oren-Nayar as pbrt-v3
// evaluates it.
Vec3f Bsdf::diffuseEval(Vec3f wo, Vec3f wi) const {
  if (wo.z <= 0 || wi.z <= 0) return Vec3f(0);
  if (orenB_ == 0) return color_ * (wi.z / kPi);
  const float sinI = std::sqrt(std::max(0.0f, 1 - wi.z * wi.z));
  const float sinO = std::sqrt(std::max(0.0f, 1 - wo.z * wo.z));
  float maxCos = 0;  // max(0, cos(phi_i - phi_o))
  if (sinI > 1e-4f && sinO > 1e-4f)
    maxCos = std::max(0.0f, (wi.x * wo.x + wi.y * wo.y) / (sinI * sinO));
  float sinAlpha, tanBeta;
  if (wi.z > wo.z) {
    sinAlpha = sinO;
    tanBeta = sinI / wi.z;
  } else {
    sinAlpha = sinI;
    tanBeta = sinO / wo.z;
  }
  return color_ * ((orenA_ + orenB_ * maxCos * sinAlpha * tanBeta) * wi.z / kPi);
}

Vec3f Bsdf::coatEval(Vec3f wo, Vec3f wi) const {
  if (wo.z <= 0 || wi.z <= 0) return Vec3f(0);
  if (fresnelBlend_) {
    // pbrt-v3's FresnelBlend::f, times cos(wi).
    auto pow5 = [](float v) { return (v * v) * (v * v) * v; };
    const Vec3f base =
        color_ * (Vec3f(1) - specular_) *
        (28 / (23 * kPi) * (1 - pow5(1 - 0.5f * wi.z)) * (1 - pow5(1 - 0.5f * wo.z)));
    const Vec3f m = normalize(wo + wi);
    const float cosIM = dot(wi, m);
    if (!(cosIM > 0)) return base * wi.z;
    const Vec3f schlickF = specular_ + (Vec3f(1) - specular_) * pow5(1 - cosIM);
    return base * wi.z + schlickF * (ggxD(m, alpha_) / (4 * cosIM * std::max(wi.z, wo.z)) * wi.z);
  }
  Vec3f base =
      baseAlpha_ > 0 ? roughConductorEval(wo, wi, color_, baseAlpha_) : diffuseEval(wo, wi);
  if (layered_)
    base = base * ((1 - fresnelDielectric(wo.z, ior_)) * (1 - fresnelDielectric(wi.z, ior_)));
  const Vec3f m = normalize(wo + wi);
  // pbrt's MicrofacetReflection: F at the microfacet, cos(wi, m).
  const float f = fresnelDielectric(dot(wi, m), ior_);
  return base + specular_ * (f * ggxD(m, alpha_) * ggxG2(wo, wi, alpha_) / (4 * wo.z));
}

float Bsdf::coatPdf(Vec3f wo, Vec3f wi) const {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  const Vec3f m = normalize(wo + wi);
  const float cosOM = dot(wo, m);
  const float glossy = cosOM > 0 ? visibleNormalPdf(wo, m, alpha_) / (4 * cosOM) : 0;
  const float base = baseAlpha_ > 0 ? roughConductorPdf(wo, wi, baseAlpha_) : wi.z / kPi;
  return coatProbability_ * glossy + (1 - coatProbability_) * base;
}

Bsdf Bsdf::conductor(Vec3f f0, float roughness) {
  Bsdf b;
  b.alpha_ = std::max(roughness * roughness, 0.0f);
  b.kind_ = b.alpha_ < kSmoothAlpha ? Kind::SmoothConductor : Kind::RoughConductor;
  b.color_ = f0;
  return b;
}

Bsdf Bsdf::dielectric(float ior, float roughness, Vec3f tint) {
  Bsdf b;
  b.alpha_ = std::max(roughness * roughness, 0.0f);
  b.kind_ = b.alpha_ < kSmoothAlpha ? Kind::SmoothDielectric : Kind::RoughDielectric;
  b.ior_ = ior > 0 ? ior : 1.5f;
  b.color_ = tint;
  return b;
}

Bsdf Bsdf::diffuseTransmission(Vec3f reflectance, Vec3f transmittance) {
  Bsdf b;
  b.kind_ = Kind::DiffuseTransmission;
  b.color_ = max(reflectance, Vec3f(0));
  b.specular_ = max(transmittance, Vec3f(0));
  const float r = maxComponent(b.color_), t = maxComponent(b.specular_);
  b.coatProbability_ = r + t > 0 ? t / (r + t) : 0;  // the probability of transmitting
  return b;
}

Bsdf Bsdf::fourier(const FourierBsdfTable& table) {
  Bsdf b;
  b.kind_ = Kind::Fourier;
  b.table_ = &table;
  b.tableTransmits_ = table.transmits();
  return b;
}

// A table names the BSDF outright; else chosen by the dominant parameter:
// glass, metal, a coated base, or diffuse (a glTF blend of metal and
// dielectric takes the larger).
Bsdf Bsdf::fromMaterial(const Material& material, Vec3f color, const FourierBsdfTable* table) {
  if (table) return fourier(*table);
  if (material.transmission >= 0.5f) return dielectric(material.ior, material.roughness, color);
  if (material.metallic >= 0.5f && maxComponent(material.specular) > 0)
    return coatedConductor(color, material.roughness, material.specular, material.specularRoughness,
                           material.specularEta);
  if (material.metallic >= 0.5f) return conductor(color, material.roughness);
  if (maxComponent(material.transmittance) > 0)
    return diffuseTransmission(color, material.transmittance);
  if (maxComponent(material.specular) > 0 && material.coat == Material::Coat::FresnelBlend)
    return fresnelBlend(color, material.specular, material.specularRoughness);
  if (maxComponent(material.specular) > 0)
    return coated(color, material.specular, material.specularRoughness, material.specularEta,
                  material.coat == Material::Coat::Layered, material.sigma);
  return diffuse(color, material.sigma);
}

Vec3f Bsdf::eval(Vec3f wo, Vec3f wi) const {
  switch (kind_) {
    case Kind::DiffuseTransmission:
      if (wo.z == 0 || wi.z == 0) return Vec3f(0);
      return (wo.z * wi.z > 0 ? color_ : specular_) * (std::abs(wi.z) / kPi);
    case Kind::Diffuse:
      return diffuseEval(wo, wi);
    case Kind::Coated:
      return coatEval(wo, wi);
    case Kind::Fourier:
      return fourierEval(*table_, wo, wi);
    case Kind::RoughConductor:
      return roughConductorEval(wo, wi, color_, alpha_);
    case Kind::RoughDielectric: {
      if (wo.z == 0 || wi.z == 0) return Vec3f(0);
      // Work on the side of wo.
      bool outside = wo.z > 0;
      float eta = outside ? ior_ : 1 / ior_;
      Vec3f o = outside ? wo : -wo;
      Vec3f i = outside ? wi : -wi;
      if (i.z > 0) {  // reflection
        Vec3f m = normalize(o + i);
        float f = fresnelDielectric(dot(o, m), eta);
        return Vec3f(f * ggxD(m, alpha_) * ggxG2(o, i, alpha_) / (4 * o.z));
      }
      Vec3f m = normalize(o + i * eta) * -1.0f;
      if (m.z < 0) m = -m;
      float cosOM = dot(o, m), cosIM = dot(i, m);
      if (cosOM <= 0 || cosIM >= 0) return Vec3f(0);
      float f = fresnelDielectric(cosOM, eta);
      float denom = cosOM + eta * cosIM;
      float value = std::abs(cosIM) * cosOM * eta * eta * (1 - f) * ggxD(m, alpha_) *
                    ggxG2(o, i, alpha_) / (o.z * denom * denom);
      return color_ * value;
    }
    default:
      return Vec3f(0);
  }
}

float Bsdf::pdf(Vec3f wo, Vec3f wi) const {
  switch (kind_) {
    case Kind::DiffuseTransmission:
      if (wo.z == 0 || wi.z == 0) return 0;
      return (wo.z * wi.z > 0 ? 1 - coatProbability_ : coatProbability_) * std::abs(wi.z) / kPi;
    case Kind::Diffuse:
      if (wo.z <= 0 || wi.z <= 0) return 0;
      return wi.z / kPi;
    case Kind::Coated:
      return coatPdf(wo, wi);
    case Kind::Fourier:
      return fourierPdf(*table_, wo, wi);
    case Kind::RoughConductor:
      return roughConductorPdf(wo, wi, alpha_);
    case Kind::RoughDielectric: {
      if (wo.z == 0 || wi.z == 0) return 0;
      bool outside = wo.z > 0;
      float eta = outside ? ior_ : 1 / ior_;
      Vec3f o = outside ? wo : -wo;
      Vec3f i = outside ? wi : -wi;
      if (i.z > 0) {
        Vec3f m = normalize(o + i);
        float cosOM = dot(o, m);
        if (cosOM <= 0) return 0;
        float f = fresnelDielectric(cosOM, eta);
        return visibleNormalPdf(o, m, alpha_) * f / (4 * cosOM);
      }
      Vec3f m = normalize(o + i * eta) * -1.0f;
      if (m.z < 0) m = -m;
      float cosOM = dot(o, m), cosIM = dot(i, m);
      if (cosOM <= 0 || cosIM >= 0) return 0;
      float f = fresnelDielectric(cosOM, eta);
      float denom = cosOM + eta * cosIM;
      return visibleNormalPdf(o, m, alpha_) * (1 - f) * eta * eta * std::abs(cosIM) /
             (denom * denom);
    }
    default:
      return 0;
  }
}

bool Bsdf::sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
  switch (kind_) {
    case Kind::DiffuseTransmission: {
      if (wo.z == 0) return false;
      const bool transmit = uLobe < coatProbability_;
      out.wi = sampleCosineHemisphere(u);
      if (out.wi.z <= 0) return false;
      if ((wo.z < 0) != transmit) out.wi.z = -out.wi.z;  // onto wo's side, or through
      out.pdf = pdf(wo, out.wi);
      if (!(out.pdf > 0)) return false;
      out.weight = eval(wo, out.wi) * (1 / out.pdf);
      out.delta = false;
      return true;
    }
    case Kind::Diffuse: {
      if (wo.z <= 0) return false;
      out.wi = sampleCosineHemisphere(u);
      if (out.wi.z <= 0) return false;
      out.pdf = out.wi.z / kPi;
      // eval / pdf: the albedo times Oren-Nayar's factor (1 for Lambertian).
      out.weight = orenB_ == 0 ? color_ : diffuseEval(wo, out.wi) * (kPi / out.wi.z);
      out.delta = false;
      return true;
    }
    case Kind::Coated: {
      if (wo.z <= 0) return false;
      if (uLobe < coatProbability_ || baseAlpha_ > 0) {
        // The coat's microfacets, or the conductor base's.
        const float alpha = uLobe < coatProbability_ ? alpha_ : baseAlpha_;
        out.wi = reflect(wo, sampleVisibleNormal(wo, alpha, u));
      } else {
        out.wi = sampleCosineHemisphere(u);
      }
      if (out.wi.z <= 0) return false;
      out.pdf = coatPdf(wo, out.wi);
      if (!(out.pdf > 0)) return false;
      out.weight = coatEval(wo, out.wi) * (1 / out.pdf);
      out.delta = false;
      return true;
    }
    case Kind::Fourier:
      return fourierSample(*table_, wo, u, out);
    case Kind::SmoothConductor: {
      if (wo.z <= 0) return false;
      out.wi = {-wo.x, -wo.y, wo.z};
      out.pdf = 1;
      out.weight = schlick(color_, wo.z);
      out.delta = true;
      return true;
    }
    case Kind::RoughConductor: {
      if (wo.z <= 0) return false;
      Vec3f m = sampleVisibleNormal(wo, alpha_, u);
      out.wi = reflect(wo, m);
      if (out.wi.z <= 0) return false;
      out.pdf = visibleNormalPdf(wo, m, alpha_) / (4 * dot(wo, m));
      out.weight = schlick(color_, dot(wo, m)) * (ggxG2(wo, out.wi, alpha_) / ggxG1(wo, alpha_));
      out.delta = false;
      return true;
    }
    case Kind::SmoothDielectric:
    case Kind::RoughDielectric: {
      if (wo.z == 0) return false;
      bool outside = wo.z > 0;
      float eta = outside ? ior_ : 1 / ior_;
      Vec3f o = outside ? wo : -wo;
      bool smooth = kind_ == Kind::SmoothDielectric;
      Vec3f m = smooth ? Vec3f(0, 0, 1) : sampleVisibleNormal(o, alpha_, u);
      float cosOM = dot(o, m);
      if (cosOM <= 0) return false;
      float f = fresnelDielectric(cosOM, eta);
      Vec3f i;
      bool reflected = uLobe < f;
      if (reflected) {
        i = reflect(o, m);
        if (i.z <= 0) return false;
      } else {
        if (!refract(o, m, eta, i) || i.z >= 0) return false;
      }
      out.wi = outside ? i : -i;
      out.delta = smooth;
      if (smooth) {
        out.pdf = 1;
        out.weight = reflected ? Vec3f(1) : color_;
      } else {
        out.pdf = pdf(wo, out.wi);
        float g = ggxG2(o, i, alpha_) / ggxG1(o, alpha_);
        out.weight = (reflected ? Vec3f(1) : color_) * g;
        if (out.pdf <= 0) return false;
      }
      return true;
    }
  }
  return false;
}

}  // namespace ferry
