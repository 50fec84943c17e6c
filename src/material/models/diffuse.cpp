#include "material/models/diffuse.h"

#include <cmath>

#include <fmt/format.h>

namespace ferry {

DiffuseLobe::DiffuseLobe(Vec3f albedo, float sigmaDegrees) : color(albedo) {
  if (sigmaDegrees > 0) {
    // pbrt-v3's OrenNayar constructor.
    const float sigma = sigmaDegrees * (kPi / 180), sigma2 = sigma * sigma;
    orenA = 1 - sigma2 / (2 * (sigma2 + 0.33f));
    orenB = 0.45f * sigma2 / (sigma2 + 0.09f);
  }
}

// Lambertian, or Oren-Nayar as pbrt-v3 evaluates it.
Vec3f DiffuseLobe::eval(Vec3f wo, Vec3f wi) const {
  if (wo.z <= 0 || wi.z <= 0) return Vec3f(0);
  if (orenB == 0) return color * (wi.z / kPi);
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
  return color * ((orenA + orenB * maxCos * sinAlpha * tanBeta) * wi.z / kPi);
}

float DiffuseLobe::pdf(Vec3f wo, Vec3f wi) const {
  if (wo.z <= 0 || wi.z <= 0) return 0;
  return wi.z / kPi;
}

bool DiffuseLobe::sample(Vec3f wo, float, Vec2f u, BsdfSample& out) const {
  if (wo.z <= 0) return false;
  out.wi = sampleCosineHemisphere(u);
  if (out.wi.z <= 0) return false;
  out.pdf = out.wi.z / kPi;
  // eval / pdf: the albedo times Oren-Nayar's factor (1 for Lambertian).
  out.weight = orenB == 0 ? color : eval(wo, out.wi) * (kPi / out.wi.z);
  out.delta = false;
  return true;
}

Bsdf diffuseBsdf(Vec3f albedo, float sigmaDegrees) {
  return Bsdf(DiffuseLobe(albedo, sigmaDegrees), false, false);
}

std::shared_ptr<const MaterialModel> DiffuseModel::read(MaterialRecordReader& record) {
  const float sigma = record.number();
  if (!(sigma >= 0 && sigma <= 90)) record.fail(fmt::format("sigma {} is outside [0, 90]", sigma));
  return std::make_shared<DiffuseModel>(sigma);
}

std::string DiffuseModel::describe() const {
  return sigmaDegrees > 0 ? fmt::format("diffuse (Oren-Nayar, sigma {:g} degrees)", sigmaDegrees)
                          : "diffuse (Lambertian)";
}

}  // namespace ferry
