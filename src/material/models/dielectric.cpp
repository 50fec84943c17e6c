#include "material/models/dielectric.h"

#include <fmt/format.h>

#include "material/microfacet.h"

namespace ferry {
namespace {

using namespace microfacet;

struct DielectricLobe {
  Vec3f tint;
  float alpha;
  float ior;
  bool smooth;

  Vec3f eval(Vec3f wo, Vec3f wi) const {
    if (smooth || wo.z == 0 || wi.z == 0) return Vec3f(0);
    // Work on the side of wo.
    bool outside = wo.z > 0;
    float eta = outside ? ior : 1 / ior;
    Vec3f o = outside ? wo : -wo;
    Vec3f i = outside ? wi : -wi;
    if (i.z > 0) {  // reflection
      Vec3f m = normalize(o + i);
      float f = fresnelDielectric(dot(o, m), eta);
      return Vec3f(f * ggxD(m, alpha) * ggxG2(o, i, alpha) / (4 * o.z));
    }
    Vec3f m = normalize(o + i * eta) * -1.0f;
    if (m.z < 0) m = -m;
    float cosOM = dot(o, m), cosIM = dot(i, m);
    if (cosOM <= 0 || cosIM >= 0) return Vec3f(0);
    float f = fresnelDielectric(cosOM, eta);
    float denom = cosOM + eta * cosIM;
    float value = std::abs(cosIM) * cosOM * eta * eta * (1 - f) * ggxD(m, alpha) *
                  ggxG2(o, i, alpha) / (o.z * denom * denom);
    return tint * value;
  }

  float pdf(Vec3f wo, Vec3f wi) const {
    if (smooth || wo.z == 0 || wi.z == 0) return 0;
    bool outside = wo.z > 0;
    float eta = outside ? ior : 1 / ior;
    Vec3f o = outside ? wo : -wo;
    Vec3f i = outside ? wi : -wi;
    if (i.z > 0) {
      Vec3f m = normalize(o + i);
      float cosOM = dot(o, m);
      if (cosOM <= 0) return 0;
      float f = fresnelDielectric(cosOM, eta);
      return visibleNormalPdf(o, m, alpha) * f / (4 * cosOM);
    }
    Vec3f m = normalize(o + i * eta) * -1.0f;
    if (m.z < 0) m = -m;
    float cosOM = dot(o, m), cosIM = dot(i, m);
    if (cosOM <= 0 || cosIM >= 0) return 0;
    float f = fresnelDielectric(cosOM, eta);
    float denom = cosOM + eta * cosIM;
    return visibleNormalPdf(o, m, alpha) * (1 - f) * eta * eta * std::abs(cosIM) / (denom * denom);
  }

  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
    if (wo.z == 0) return false;
    bool outside = wo.z > 0;
    float eta = outside ? ior : 1 / ior;
    Vec3f o = outside ? wo : -wo;
    Vec3f m = smooth ? Vec3f(0, 0, 1) : sampleVisibleNormal(o, alpha, u);
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
      out.weight = reflected ? Vec3f(1) : tint;
    } else {
      out.pdf = pdf(wo, out.wi);
      float g = ggxG2(o, i, alpha) / ggxG1(o, alpha);
      out.weight = (reflected ? Vec3f(1) : tint) * g;
      if (out.pdf <= 0) return false;
    }
    return true;
  }
};

}  // namespace

Bsdf dielectricBsdf(float ior, float roughness, Vec3f tint) {
  DielectricLobe lobe;
  lobe.alpha = std::max(roughness * roughness, 0.0f);
  lobe.smooth = lobe.alpha < kSmoothAlpha;
  lobe.ior = ior > 0 ? ior : 1.5f;
  lobe.tint = tint;
  return Bsdf(lobe, lobe.smooth, true);
}

std::shared_ptr<const MaterialModel> DielectricModel::read(MaterialRecordReader& record) {
  const float ior = record.number();
  const float roughness = record.number();
  return std::make_shared<DielectricModel>(ior, roughness);
}

std::string DielectricModel::describe() const {
  return fmt::format("dielectric (ior {:g}, roughness {:g})", ior, roughness);
}

}  // namespace ferry
