#include "material/models/diffuse_transmission.h"

#include <fmt/format.h>

#include "material/models/diffuse.h"

namespace ferry {
namespace {

struct DiffuseTransmissionLobe {
  Vec3f reflectance, transmittance;
  float transmitProbability;

  Vec3f eval(Vec3f wo, Vec3f wi) const {
    if (wo.z == 0 || wi.z == 0) return Vec3f(0);
    return (wo.z * wi.z > 0 ? reflectance : transmittance) * (std::abs(wi.z) / kPi);
  }
  float pdf(Vec3f wo, Vec3f wi) const {
    if (wo.z == 0 || wi.z == 0) return 0;
    return (wo.z * wi.z > 0 ? 1 - transmitProbability : transmitProbability) * std::abs(wi.z) / kPi;
  }
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
    if (wo.z == 0) return false;
    const bool transmit = uLobe < transmitProbability;
    out.wi = sampleCosineHemisphere(u);
    if (out.wi.z <= 0) return false;
    if ((wo.z < 0) != transmit) out.wi.z = -out.wi.z;  // onto wo's side, or through
    out.pdf = pdf(wo, out.wi);
    if (!(out.pdf > 0)) return false;
    out.weight = eval(wo, out.wi) * (1 / out.pdf);
    out.delta = false;
    return true;
  }
};

}  // namespace

Bsdf diffuseTransmissionBsdf(Vec3f reflectance, Vec3f transmittance) {
  DiffuseTransmissionLobe lobe;
  lobe.reflectance = max(reflectance, Vec3f(0));
  lobe.transmittance = max(transmittance, Vec3f(0));
  const float r = maxComponent(lobe.reflectance), t = maxComponent(lobe.transmittance);
  lobe.transmitProbability = r + t > 0 ? t / (r + t) : 0;
  return Bsdf(lobe, false, true);
}

Bsdf DiffuseTransmissionModel::bsdf(Vec3f color, const MaterialResources&) const {
  if (!(maxComponent(transmittance) > 0)) return diffuseBsdf(color);
  return diffuseTransmissionBsdf(color, transmittance);
}

std::shared_ptr<const MaterialModel> DiffuseTransmissionModel::read(MaterialRecordReader& record) {
  return std::make_shared<DiffuseTransmissionModel>(record.color());
}

std::string DiffuseTransmissionModel::describe() const {
  return fmt::format("diffuse transmission (transmittance ({:g}, {:g}, {:g}))", transmittance.x,
                     transmittance.y, transmittance.z);
}

}  // namespace ferry
