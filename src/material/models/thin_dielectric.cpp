#include "material/models/thin_dielectric.h"

#include <fmt/format.h>

#include <cmath>

namespace ferry {
namespace {

struct ThinDielectricLobe {
  float ior;
  Vec3f tint;

  // The sheet's reflectance at |cos theta| = c, its inter-reflections included.
  float reflectance(float c) const {
    float r = fresnelDielectric(std::abs(c), ior);
    if (r < 1) r += (1 - r) * (1 - r) * r / (1 - r * r);
    return r;
  }
  Vec3f eval(Vec3f, Vec3f) const { return Vec3f(0); }
  float pdf(Vec3f, Vec3f) const { return 0; }
  bool sample(Vec3f wo, float uLobe, Vec2f, BsdfSample& out) const {
    if (wo.z == 0) return false;
    const float r = reflectance(wo.z);
    out.delta = true;
    if (uLobe < r) {
      out.wi = {-wo.x, -wo.y, wo.z};
      out.weight = Vec3f(1);
      out.pdf = r;
    } else {
      out.wi = -wo;
      out.weight = tint;
      out.pdf = 1 - r;
    }
    return true;
  }
};

}  // namespace

Bsdf thinDielectricBsdf(float ior, Vec3f tint) {
  return Bsdf(ThinDielectricLobe{ior > 0 ? ior : 1.5f, tint}, true, true);
}

std::shared_ptr<const MaterialModel> ThinDielectricModel::read(MaterialRecordReader& record) {
  const float ior = record.number();
  if (!(ior > 0)) record.fail(fmt::format("thin dielectric index {} is not positive", ior));
  return std::make_shared<ThinDielectricModel>(ior);
}

std::string ThinDielectricModel::describe() const {
  return fmt::format("thin dielectric (ior {:g})", ior);
}

}  // namespace ferry
