#include "material/models/conductor.h"

#include <fmt/format.h>

#include "material/microfacet.h"

namespace ferry {
namespace {

using namespace microfacet;

struct MirrorLobe {
  Vec3f f0;
  Vec3f eval(Vec3f, Vec3f) const { return Vec3f(0); }
  float pdf(Vec3f, Vec3f) const { return 0; }
  bool sample(Vec3f wo, float, Vec2f, BsdfSample& out) const {
    if (wo.z <= 0) return false;
    out.wi = {-wo.x, -wo.y, wo.z};
    out.pdf = 1;
    out.weight = schlick(f0, wo.z);
    out.delta = true;
    return true;
  }
};

struct RoughConductorLobe {
  Vec3f f0;
  float alpha;
  Vec3f eval(Vec3f wo, Vec3f wi) const { return roughConductorEval(wo, wi, f0, alpha); }
  float pdf(Vec3f wo, Vec3f wi) const { return roughConductorPdf(wo, wi, alpha); }
  bool sample(Vec3f wo, float, Vec2f u, BsdfSample& out) const {
    if (wo.z <= 0) return false;
    Vec3f m = sampleVisibleNormal(wo, alpha, u);
    out.wi = reflect(wo, m);
    if (out.wi.z <= 0) return false;
    out.pdf = visibleNormalPdf(wo, m, alpha) / (4 * dot(wo, m));
    out.weight = schlick(f0, dot(wo, m)) * (ggxG2(wo, out.wi, alpha) / ggxG1(wo, alpha));
    out.delta = false;
    return true;
  }
};

}  // namespace

Bsdf conductorBsdf(Vec3f f0, float roughness) {
  const float alpha = std::max(roughness * roughness, 0.0f);
  if (alpha < kSmoothAlpha) return Bsdf(MirrorLobe{f0}, true, false);
  return Bsdf(RoughConductorLobe{f0, alpha}, false, false);
}

std::shared_ptr<const MaterialModel> ConductorModel::read(MaterialRecordReader& record) {
  return std::make_shared<ConductorModel>(record.number());
}

std::string ConductorModel::describe() const {
  return fmt::format("conductor (roughness {:g})", roughness);
}

}  // namespace ferry
