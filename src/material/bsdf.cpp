#include "material/bsdf.h"

#include <algorithm>
#include <cmath>

namespace ferry {
namespace {

// What a default Bsdf holds: a black surface.
struct BlackLobe {
  Vec3f eval(Vec3f, Vec3f) const { return Vec3f(0); }
  float pdf(Vec3f, Vec3f) const { return 0; }
  bool sample(Vec3f, float, Vec2f, BsdfSample&) const { return false; }
};

}  // namespace

Bsdf::Bsdf() : Bsdf(BlackLobe{}, false, false) {}

float fresnelDielectric(float cosI, float eta) {
  cosI = std::clamp(cosI, 0.0f, 1.0f);
  float sin2T = (1 - cosI * cosI) / (eta * eta);
  if (sin2T >= 1) return 1;
  float cosT = std::sqrt(1 - sin2T);
  float rs = (cosI - eta * cosT) / (cosI + eta * cosT);
  float rp = (eta * cosI - cosT) / (eta * cosI + cosT);
  return 0.5f * (rs * rs + rp * rp);
}

}  // namespace ferry
