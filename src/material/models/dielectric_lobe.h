// The dielectric interface's lobe (material/models/dielectric.h), for models
// that are such an interface on one side (subsurface.h).
#pragma once

#include "material/bsdf.h"
#include "material/microfacet.h"

namespace ferry {

struct DielectricLobe {
  Vec3f tint;
  float alpha;
  float ior;
  bool smooth;

  // `roughness`: Ferry's (GGX alpha = roughness^2), smooth below
  // kSmoothAlpha; an ior <= 0 is 1.5.
  static DielectricLobe make(float ior, float roughness, Vec3f tint) {
    DielectricLobe lobe;
    lobe.alpha = std::max(roughness * roughness, 0.0f);
    lobe.smooth = lobe.alpha < microfacet::kSmoothAlpha;
    lobe.ior = ior > 0 ? ior : 1.5f;
    lobe.tint = tint;
    return lobe;
  }

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
      return Vec3f(f * microfacet::ggxD(m, alpha) * microfacet::ggxG2(o, i, alpha) / (4 * o.z));
    }
    Vec3f m = normalize(o + i * eta) * -1.0f;
    if (m.z < 0) m = -m;
    float cosOM = dot(o, m), cosIM = dot(i, m);
    if (cosOM <= 0 || cosIM >= 0) return Vec3f(0);
    float f = fresnelDielectric(cosOM, eta);
    float denom = cosOM + eta * cosIM;
    float value = std::abs(cosIM) * cosOM * eta * eta * (1 - f) * microfacet::ggxD(m, alpha) *
                  microfacet::ggxG2(o, i, alpha) / (o.z * denom * denom);
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
      return microfacet::visibleNormalPdf(o, m, alpha) * f / (4 * cosOM);
    }
    Vec3f m = normalize(o + i * eta) * -1.0f;
    if (m.z < 0) m = -m;
    float cosOM = dot(o, m), cosIM = dot(i, m);
    if (cosOM <= 0 || cosIM >= 0) return 0;
    float f = fresnelDielectric(cosOM, eta);
    float denom = cosOM + eta * cosIM;
    return microfacet::visibleNormalPdf(o, m, alpha) * (1 - f) * eta * eta * std::abs(cosIM) /
           (denom * denom);
  }

  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
    if (wo.z == 0) return false;
    bool outside = wo.z > 0;
    float eta = outside ? ior : 1 / ior;
    Vec3f o = outside ? wo : -wo;
    Vec3f m = smooth ? Vec3f(0, 0, 1) : microfacet::sampleVisibleNormal(o, alpha, u);
    float cosOM = dot(o, m);
    if (cosOM <= 0) return false;
    float f = fresnelDielectric(cosOM, eta);
    Vec3f i;
    bool reflected = uLobe < f;
    if (reflected) {
      i = microfacet::reflect(o, m);
      if (i.z <= 0) return false;
    } else {
      if (!microfacet::refract(o, m, eta, i) || i.z >= 0) return false;
    }
    out.wi = outside ? i : -i;
    out.delta = smooth;
    if (smooth) {
      out.pdf = 1;
      out.weight = reflected ? Vec3f(1) : tint;
    } else {
      out.pdf = pdf(wo, out.wi);
      float g = microfacet::ggxG2(o, i, alpha) / microfacet::ggxG1(o, alpha);
      out.weight = (reflected ? Vec3f(1) : tint) * g;
      if (out.pdf <= 0) return false;
    }
    return true;
  }
};

}  // namespace ferry
