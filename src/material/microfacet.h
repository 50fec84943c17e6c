// The pieces rough lobes share: the GGX (Trowbridge-Reitz) distribution, its
// Smith masking, Heitz's visible-normal sampling, mirror reflection,
// refraction and Schlick's Fresnel. Inline: every rough lobe evaluates them
// at every path vertex.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace ferry::microfacet {

// Below this GGX width a lobe is treated as a perfect mirror or window.
constexpr float kSmoothAlpha = 1e-3f;

inline float ggxD(Vec3f m, float alpha) {
  if (m.z <= 0) return 0;
  float a2 = alpha * alpha;
  float c2 = m.z * m.z;
  float d = c2 * (a2 - 1) + 1;
  return a2 / (kPi * d * d);
}

inline float ggxLambda(Vec3f w, float alpha) {
  float c2 = w.z * w.z;
  if (c2 >= 1) return 0;
  float tan2 = (1 - c2) / std::max(c2, 1e-12f);
  return 0.5f * (-1 + std::sqrt(1 + alpha * alpha * tan2));
}

inline float ggxG1(Vec3f w, float alpha) {
  return 1 / (1 + ggxLambda(w, alpha));
}
inline float ggxG2(Vec3f wo, Vec3f wi, float alpha) {
  return 1 / (1 + ggxLambda(wo, alpha) + ggxLambda(wi, alpha));
}

// Density of visible normals seen from wo (wo.z > 0).
inline float visibleNormalPdf(Vec3f wo, Vec3f m, float alpha) {
  float cosOM = dot(wo, m);
  if (cosOM <= 0 || wo.z <= 0) return 0;
  return ggxG1(wo, alpha) * cosOM * ggxD(m, alpha) / wo.z;
}

// Heitz 2018, "Sampling the GGX Distribution of Visible Normals".
inline Vec3f sampleVisibleNormal(Vec3f wo, float alpha, Vec2f u) {
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

inline Vec3f reflect(Vec3f wo, Vec3f m) {
  return m * (2 * dot(wo, m)) - wo;
}

// Refracts wo (on the side m points to) through the interface; eta = n_t / n_i.
inline bool refract(Vec3f wo, Vec3f m, float eta, Vec3f& wi) {
  float cosI = dot(wo, m);
  float sin2T = (1 - cosI * cosI) / (eta * eta);
  if (sin2T >= 1) return false;
  float cosT = std::sqrt(1 - sin2T);
  wi = -wo * (1 / eta) + m * (cosI / eta - cosT);
  return true;
}

inline Vec3f schlick(Vec3f f0, float cosTheta) {
  float c = std::clamp(1 - cosTheta, 0.0f, 1.0f);
  float c5 = c * c * c * c * c;
  return f0 + (Vec3f(1) - f0) * c5;
}

// A GGX conductor's f * cos(wi) and sampling density (visible normals).
inline Vec3f roughConductorEval(Vec3f wo, Vec3f wi, Vec3f f0, float alpha) {
  if (wo.z <= 0 || wi.z <= 0) return Vec3f(0);
  const Vec3f m = normalize(wo + wi);
  return schlick(f0, dot(wo, m)) * (ggxD(m, alpha) * ggxG2(wo, wi, alpha) / (4 * wo.z));
}
inline float roughConductorPdf(Vec3f wo, Vec3f wi, float alpha) {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  const Vec3f m = normalize(wo + wi);
  const float cosOM = dot(wo, m);
  return cosOM > 0 ? visibleNormalPdf(wo, m, alpha) / (4 * cosOM) : 0;
}

}  // namespace ferry::microfacet
