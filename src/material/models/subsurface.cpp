#include "material/models/subsurface.h"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <mutex>

#include "core/catmull_rom.h"
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

// Under probes: pbrt's dielectric interface from either side, reflection
// tinted by Kr and transmission by Kt (the lobe's colour). A transmission
// either way is where the BSSRDF takes over.
struct ProbedSurfaceLobe {
  DielectricLobe surface;
  Vec3f reflectTint;

  Vec3f eval(Vec3f wo, Vec3f wi) const {
    const Vec3f f = surface.eval(wo, wi);
    return wo.z * wi.z > 0 ? f * reflectTint : f;
  }
  float pdf(Vec3f wo, Vec3f wi) const { return surface.pdf(wo, wi); }
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
    if (!surface.sample(wo, uLobe, u, out)) return false;
    if (wo.z * out.wi.z > 0) out.weight = out.weight * reflectTint;
    return true;
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

std::shared_ptr<const BssrdfTable> beamDiffusionTable(float g, float eta) {
  static std::mutex mutex;
  static std::map<std::pair<float, float>, std::shared_ptr<const BssrdfTable>> made;
  const std::lock_guard lock(mutex);
  auto& slot = made[{g, eta}];
  if (slot) return slot;
  auto t = std::make_shared<BssrdfTable>();
  constexpr int32_t na = BssrdfTable::kAlbedos, nr = BssrdfTable::kRadii;
  t->g = g;
  t->eta = eta;
  t->albedo.resize(na);
  t->radius.resize(nr);
  t->profile.resize(size_t(na) * nr);
  t->cdf.resize(size_t(na) * nr);
  t->effectiveAlbedo.resize(na);
  // Radii from 0.0025 growing by 1.2 (to about 2000 mean free paths);
  // albedos crowded towards 1, where the profile changes fastest.
  t->radius[0] = 0;
  t->radius[1] = 2.5e-3f;
  for (int32_t j = 2; j < nr; ++j) t->radius[j] = t->radius[j - 1] * 1.2f;
  for (int32_t i = 0; i < na; ++i)
    t->albedo[i] = float((1 - std::exp(-8.0 * i / (na - 1))) / (1 - std::exp(-8.0)));
  const BeamDiffusion diffusion = beamDiffusion(g, eta);
  for (int32_t i = 0; i < na; ++i) {
    float* row = &t->profile[size_t(i) * nr];
    for (int32_t j = 0; j < nr; ++j) {
      const double r = t->radius[j];
      row[j] = float(2 * kPi * r *
                     (diffusion.single(t->albedo[i], r) + diffusion.multiple(t->albedo[i], r)));
    }
    t->effectiveAlbedo[i] = integrateCatmullRom(t->radius.data(), nr, row, &t->cdf[size_t(i) * nr]);
  }
  slot = t;
  return slot;
}

namespace {

// The table's profile at (albedo, optical radius) and, optionally, the
// effective albedo at `albedo`; false outside the table.
bool interpolateProfile(const BssrdfTable& t, float albedo, float rOptical, float& profile,
                        float* effectiveAlbedo = nullptr) {
  int32_t ao, ro;
  float aw[4], rw[4];
  if (!catmullRomWeights(t.albedo.data(), BssrdfTable::kAlbedos, albedo, ao, aw) ||
      !catmullRomWeights(t.radius.data(), BssrdfTable::kRadii, rOptical, ro, rw))
    return false;
  float sum = 0, rhoEff = 0;
  for (int32_t i = 0; i < 4; ++i) {
    if (aw[i] == 0) continue;
    rhoEff += t.effectiveAlbedo[size_t(ao + i)] * aw[i];
    for (int32_t j = 0; j < 4; ++j)
      if (rw[j] != 0)
        sum += aw[i] * rw[j] * t.profile[size_t(ao + i) * BssrdfTable::kRadii + size_t(ro + j)];
  }
  // The table holds 2 pi r S(r).
  if (rOptical != 0) sum /= 2 * kPi * rOptical;
  profile = sum;
  if (effectiveAlbedo) *effectiveAlbedo = rhoEff;
  return true;
}

}  // namespace

Vec3f SubsurfaceProfile::sr(float r) const {
  Vec3f out(0);
  for (int ch = 0; ch < 3; ++ch) {
    float v;
    if (!interpolateProfile(*table, albedo[ch], r * sigmaT[ch], v)) continue;
    out[ch] = std::max(0.0f, v * sigmaT[ch] * sigmaT[ch]);
  }
  return out;
}

float SubsurfaceProfile::sampleSr(int ch, float u) const {
  if (!(sigmaT[ch] > 0)) return -1;
  float x;
  if (!sampleCatmullRom2D(table->albedo.data(), BssrdfTable::kAlbedos, table->radius.data(),
                          BssrdfTable::kRadii, table->profile.data(), table->cdf.data(), albedo[ch],
                          u, x))
    return -1;
  return x / sigmaT[ch];
}

float SubsurfaceProfile::pdfSr(int ch, float r) const {
  float v, rhoEff;
  if (!interpolateProfile(*table, albedo[ch], r * sigmaT[ch], v, &rhoEff) || !(rhoEff > 0))
    return 0;
  return std::max(0.0f, v * sigmaT[ch] * sigmaT[ch] / rhoEff);
}

bool sampleProbeSegment(const SubsurfaceProfile& profile, Vec3f entry, const Frame& frame,
                        float uAxis, Vec2f u, ProbeSegment& out) {
  Vec3f vx, vy, vz;
  float uChannel;
  if (uAxis < 0.5f) {
    vx = frame.s, vy = frame.t, vz = frame.n;
    uChannel = uAxis * 2;
  } else if (uAxis < 0.75f) {
    vx = frame.t, vy = frame.n, vz = frame.s;
    uChannel = (uAxis - 0.5f) * 4;
  } else {
    vx = frame.n, vy = frame.s, vz = frame.t;
    uChannel = (uAxis - 0.75f) * 4;
  }
  const int ch = std::clamp(int(uChannel * 3), 0, 2);
  const float r = profile.sampleSr(ch, u.x);
  if (!(r >= 0)) return false;
  const float rMax = profile.sampleSr(ch, 0.999f);
  if (!(r < rMax)) return false;
  const float phi = 2 * kPi * u.y;
  const float length = 2 * std::sqrt(rMax * rMax - r * r);
  out.start = entry + (vx * std::cos(phi) + vy * std::sin(phi)) * r - vz * (0.5f * length);
  out.end = out.start + vz * length;
  return true;
}

float probeDensity(const SubsurfaceProfile& profile, Vec3f entry, const Frame& frame, Vec3f exit,
                   Vec3f exitNormal) {
  const Vec3f d = frame.toLocal(exit - entry);
  const Vec3f n = frame.toLocal(exitNormal);
  const float rProjected[3] = {std::sqrt(d.y * d.y + d.z * d.z), std::sqrt(d.z * d.z + d.x * d.x),
                               std::sqrt(d.x * d.x + d.y * d.y)};
  const float axisProbability[3] = {0.25f, 0.25f, 0.5f};
  float pdf = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int ch = 0; ch < 3; ++ch)
      pdf += profile.pdfSr(ch, rProjected[axis]) * std::abs(n[axis]) * (1.0f / 3) *
             axisProbability[axis];
  return pdf;
}

Vec3f SubsurfaceExitLobe::eval(Vec3f, Vec3f wi) const {
  if (!(wi.z > 0)) return Vec3f(0);
  return Vec3f((1 - fresnelDielectric(wi.z, ior)) / exitNormalization * wi.z * (1 / kPi));
}

float SubsurfaceExitLobe::pdf(Vec3f, Vec3f wi) const {
  return wi.z > 0 ? wi.z * (1 / kPi) : 0.0f;
}

bool SubsurfaceExitLobe::sample(Vec3f, float, Vec2f u, BsdfSample& out) const {
  out.wi = sampleCosineHemisphere(u);
  if (!(out.wi.z > 0)) return false;
  out.pdf = out.wi.z * (1 / kPi);
  out.weight = Vec3f((1 - fresnelDielectric(out.wi.z, ior)) / exitNormalization);
  out.delta = false;
  return out.pdf > 0;
}

SubsurfaceModel::SubsurfaceModel(float ior, float roughness, Vec3f reflectTint)
    : ior(ior), roughness(roughness), reflectTint(reflectTint) {
  exitNormalization_ = subsurfaceExitNormalization(ior);
}

SubsurfaceModel::SubsurfaceModel(float ior, float roughness, Vec3f reflectTint, Vec3f sigmaA,
                                 Vec3f sigmaS, float g, uint32_t probeId)
    : SubsurfaceModel(ior, roughness, reflectTint) {
  hasMedium = true;
  this->probeId = probeId;
  this->sigmaA = sigmaA;
  this->sigmaS = sigmaS;
  this->g = g;
  table_ = beamDiffusionTable(g, ior);
}

SubsurfaceProfile SubsurfaceModel::profile() const {
  SubsurfaceProfile p;
  p.sigmaT = sigmaA + sigmaS;
  for (int ch = 0; ch < 3; ++ch) p.albedo[ch] = p.sigmaT[ch] > 0 ? sigmaS[ch] / p.sigmaT[ch] : 0;
  p.table = table_.get();
  return p;
}

Bsdf SubsurfaceModel::bsdf(Vec3f color, const MaterialResources&) const {
  SubsurfaceLobe lobe;
  lobe.surface = DielectricLobe::make(ior, roughness, color);
  lobe.reflectTint = reflectTint;
  lobe.exitNormalization = exitNormalization_;
  return Bsdf(lobe, false, true);
}

Bsdf SubsurfaceModel::probedBsdf(Vec3f color) const {
  ProbedSurfaceLobe lobe;
  lobe.surface = DielectricLobe::make(ior, roughness, color);
  lobe.reflectTint = reflectTint;
  return Bsdf(lobe, lobe.surface.smooth, true);
}

void SubsurfaceModel::write(MaterialRecordWriter& record) const {
  record.pod(ior);
  record.pod(roughness);
  record.pod(reflectTint);
  if (!hasMedium) return;
  record.pod(sigmaA);
  record.pod(sigmaS);
  record.pod(g);
  record.pod(probeId);
}

std::shared_ptr<const MaterialModel> SubsurfaceModel::read(MaterialRecordReader& record) {
  const float ior = record.number();
  const float roughness = record.number();
  const Vec3f tint = record.pod<Vec3f>();
  if (!(ior > 1) || !(roughness >= 0) || !isFinite(tint))
    record.fail("subsurface: ior must exceed 1, roughness must not be negative");
  if (record.atEnd()) return std::make_shared<SubsurfaceModel>(ior, roughness, tint);
  const Vec3f sigmaA = record.color(), sigmaS = record.color();
  const float g = record.number();
  const auto probeId = record.pod<uint32_t>();
  if (!(minComponent(sigmaA) >= 0) || !(minComponent(sigmaS) >= 0) ||
      !(maxComponent(sigmaA + sigmaS) > 0) || !(std::abs(g) < 1))
    record.fail(
        "subsurface: its medium needs sigma_a, sigma_s >= 0, a positive extinction and "
        "|g| < 1");
  return std::make_shared<SubsurfaceModel>(ior, roughness, tint, sigmaA, sigmaS, g, probeId);
}

std::string SubsurfaceModel::describe() const {
  if (!hasMedium)
    return fmt::format(
        "subsurface (ior {:g}, roughness {:g}, Kr {:g} {:g} {:g}; a random walk through the "
        "medium inside)",
        ior, roughness, reflectTint.x, reflectTint.y, reflectTint.z);
  return fmt::format(
      "subsurface (ior {:g}, roughness {:g}, Kr {:g} {:g} {:g}, sigma_a {:g} {:g} {:g}, sigma_s "
      "{:g} {:g} {:g}, g {:g})",
      ior, roughness, reflectTint.x, reflectTint.y, reflectTint.z, sigmaA.x, sigmaA.y, sigmaA.z,
      sigmaS.x, sigmaS.y, sigmaS.z, g);
}

}  // namespace ferry
