#include "material/models/subsurface.h"

#include <fmt/format.h>

#include <cmath>

#include "material/models/dielectric_lobe.h"

namespace ferry {
namespace {

// From outside (wo.z > 0): the dielectric interface, its reflection tinted.
// From inside (wo.z < 0: a walk arriving at the surface): a mirror back in
// with probability F(cos inside, 1 / ior), else out by Sw, drawn from the
// cosine and weighed by (1 - F(cos, ior)) / c.
struct SubsurfaceLobe {
  DielectricLobe surface;
  Vec3f reflectTint;
  float exitNormalization;

  float insideReflectance(Vec3f wo) const { return fresnelDielectric(-wo.z, 1 / surface.ior); }
  float exitWeight(Vec3f wi) const {
    return (1 - fresnelDielectric(wi.z, surface.ior)) / exitNormalization;
  }

  Vec3f eval(Vec3f wo, Vec3f wi) const {
    if (wo.z > 0) {
      const Vec3f f = surface.eval(wo, wi);
      return wi.z > 0 ? f * reflectTint : f;
    }
    if (!(wo.z < 0) || !(wi.z > 0)) return Vec3f(0);
    return Vec3f((1 - insideReflectance(wo)) * exitWeight(wi) * wi.z * (1 / kPi));
  }

  float pdf(Vec3f wo, Vec3f wi) const {
    if (wo.z > 0) return surface.pdf(wo, wi);
    if (!(wo.z < 0) || !(wi.z > 0)) return 0;
    return (1 - insideReflectance(wo)) * wi.z * (1 / kPi);
  }

  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
    if (wo.z > 0) {
      if (!surface.sample(wo, uLobe, u, out)) return false;
      if (out.wi.z > 0) out.weight = out.weight * reflectTint;
      return true;
    }
    if (!(wo.z < 0)) return false;
    const float f = insideReflectance(wo);
    if (uLobe < f) {
      out.wi = Vec3f(-wo.x, -wo.y, wo.z);
      out.weight = Vec3f(1);
      out.pdf = 1;
      out.delta = true;
      return true;
    }
    out.wi = sampleCosineHemisphere(u);
    if (!(out.wi.z > 0)) return false;
    out.pdf = (1 - f) * out.wi.z * (1 / kPi);
    out.weight = Vec3f(exitWeight(out.wi));
    out.delta = false;
    return out.pdf > 0;
  }
};

// The i-th Fresnel moment of light inside a medium of index `eta` meeting
// its boundary: the integral over mu in [0, 1] of F(mu, 1 / eta) mu^i.
float fresnelMoment(float eta, int i) {
  constexpr int n = 512;
  double sum = 0;
  for (int k = 0; k < n; ++k) {
    const double mu = (k + 0.5) / n;
    sum += fresnelDielectric(float(mu), 1 / eta) * std::pow(mu, i);
  }
  return float(sum / n);
}

float henyeyGreenstein(float cosTheta, float g) {
  const float denom = 1 + g * g + 2 * g * cosTheta;
  return (1 - g * g) / (4 * kPi * denom * std::sqrt(std::max(denom, 1e-12f)));
}

// The photon beam diffusion profile at radius r (extinction 1): multiple
// scattering from dipoles along the refracted beam, and single scattering.
struct BeamDiffusion {
  float g, eta, fm1, fm2;

  double multiple(double albedo, double r) const {
    constexpr int n = 100;
    const double sigmaA = 1 - albedo, sigmaS = albedo;
    const double reducedS = sigmaS * (1 - g), reducedT = sigmaA + reducedS;
    const double reducedAlbedo = reducedS / reducedT;
    const double d = (2 * sigmaA + reducedS) / (3 * reducedT * reducedT);
    const double sigmaTr = std::sqrt(sigmaA / d);
    const double ze = -2 * d * (1 + 3 * fm2) / (1 - 2 * fm1);
    const double cPhi = 0.25 * (1 - 2 * fm1), cE = 0.5 * (1 - 3 * fm2);
    double sum = 0;
    for (int i = 0; i < n; ++i) {
      const double zr = -std::log(1 - (i + 0.5) / n) / reducedT;
      const double zv = -zr + 2 * ze;
      const double dr = std::sqrt(r * r + zr * zr), dv = std::sqrt(r * r + zv * zv);
      const double er = std::exp(-sigmaTr * dr), ev = std::exp(-sigmaTr * dv);
      const double phi = (er / dr - ev / dv) / (4 * kPi * d);
      const double flux = (zr * (1 + sigmaTr * dr) * er / (dr * dr * dr) -
                           zv * (1 + sigmaTr * dv) * ev / (dv * dv * dv)) /
                          (4 * kPi);
      const double kappa = 1 - std::exp(-2 * reducedT * (dr + zr));
      sum += kappa * reducedAlbedo * reducedAlbedo * (phi * cPhi + flux * cE);
    }
    return sum / n;
  }

  double single(double albedo, double r) const {
    constexpr int n = 100;
    const double tCrit = r * std::sqrt(std::max(double(eta) * eta - 1, 0.0));
    double sum = 0;
    for (int i = 0; i < n; ++i) {
      const double t = tCrit - std::log(1 - (i + 0.5) / n);
      const double d = std::sqrt(r * r + t * t);
      const double cosO = t / d;
      sum += albedo * std::exp(-(d + tCrit)) / (d * d) * henyeyGreenstein(float(cosO), g) *
             (1 - fresnelDielectric(float(cosO), 1 / eta)) * cosO;
    }
    return sum / n;
  }

  // The profile's integral over the plane: 2 pi r^2 S(r) over ln r.
  double reflectance(double albedo) const {
    constexpr int n = 320;
    const double lo = std::log(1e-5), hi = std::log(2e3), step = (hi - lo) / n;
    double sum = 0;
    for (int i = 0; i <= n; ++i) {
      const double r = std::exp(lo + i * step);
      const double v = 2 * kPi * r * r * (multiple(albedo, r) + single(albedo, r));
      sum += (i == 0 || i == n) ? v / 2 : v;
    }
    return sum * step;
  }
};

BeamDiffusion beamDiffusion(float g, float eta) {
  return {g, eta, fresnelMoment(eta, 1), fresnelMoment(eta, 2)};
}

}  // namespace

float subsurfaceExitNormalization(float ior) {
  return 1 - 2 * fresnelMoment(1 / ior, 1);
}

float photonBeamDiffusionReflectance(float albedo, float g, float eta) {
  return float(beamDiffusion(g, eta).reflectance(std::clamp(albedo, 0.0f, 1.0f)));
}

Vec3f subsurfaceAlbedoFromReflectance(Vec3f reflectance, float g, float eta) {
  const BeamDiffusion profile = beamDiffusion(g, eta);
  const double top = profile.reflectance(1);
  auto invert = [&](float target) {
    if (!(target > 0)) return 0.0f;
    if (target >= top) return 1.0f;
    double lo = 0, hi = 1;
    for (int i = 0; i < 24; ++i) {
      const double mid = 0.5 * (lo + hi);
      (profile.reflectance(mid) < target ? lo : hi) = mid;
    }
    return float(0.5 * (lo + hi));
  };
  return {invert(reflectance.x), invert(reflectance.y), invert(reflectance.z)};
}

SubsurfaceModel::SubsurfaceModel(float ior, float roughness, Vec3f reflectTint)
    : ior(ior), roughness(roughness), reflectTint(reflectTint) {
  exitNormalization_ = subsurfaceExitNormalization(ior);
}

Bsdf SubsurfaceModel::bsdf(Vec3f color, const MaterialResources&) const {
  SubsurfaceLobe lobe;
  lobe.surface = DielectricLobe::make(ior, roughness, color);
  lobe.reflectTint = reflectTint;
  lobe.exitNormalization = exitNormalization_;
  return Bsdf(lobe, false, true);
}

void SubsurfaceModel::write(MaterialRecordWriter& record) const {
  record.pod(ior);
  record.pod(roughness);
  record.pod(reflectTint);
}

std::shared_ptr<const MaterialModel> SubsurfaceModel::read(MaterialRecordReader& record) {
  const float ior = record.number();
  const float roughness = record.number();
  const Vec3f tint = record.pod<Vec3f>();
  if (!(ior > 1) || !(roughness >= 0) || !isFinite(tint))
    record.fail("subsurface: ior must exceed 1, roughness must not be negative");
  return std::make_shared<SubsurfaceModel>(ior, roughness, tint);
}

std::string SubsurfaceModel::describe() const {
  return fmt::format(
      "subsurface (ior {:g}, roughness {:g}, Kr {:g} {:g} {:g}; a random walk "
      "through the medium inside)",
      ior, roughness, reflectTint.x, reflectTint.y, reflectTint.z);
}

}  // namespace ferry
