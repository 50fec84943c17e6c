#include "material/models/hair.h"

#include <array>
#include <cmath>

#include <fmt/format.h>

namespace ferry {
namespace {

constexpr int kPMax = 3;

float sqr(float x) {
  return x * x;
}
float safeSqrt(float x) {
  return std::sqrt(std::max(0.0f, x));
}
float safeAsin(float x) {
  return std::asin(std::clamp(x, -1.0f, 1.0f));
}
// pbrt-v3's RGB luminance (Spectrum::y), which picks a lobe.
float lobeLuminance(Vec3f c) {
  return 0.212671f * c.x + 0.715160f * c.y + 0.072169f * c.z;
}
Vec3f expOf(Vec3f v) {
  return {std::exp(v.x), std::exp(v.y), std::exp(v.z)};
}

// The modified Bessel function I0 by its series, and its log.
float besselI0(float x) {
  float value = 0, x2i = 1;
  int64_t factorial = 1, four = 1;
  for (int i = 0; i < 10; ++i) {
    if (i > 1) factorial *= i;
    value += x2i / (float(four) * sqr(float(factorial)));
    x2i *= x * x;
    four *= 4;
  }
  return value;
}
float logBesselI0(float x) {
  if (x > 12) return x + 0.5f * (-std::log(2 * kPi) + std::log(1 / x) + 1 / (8 * x));
  return std::log(besselI0(x));
}

// The longitudinal scattering function of variance v.
float mp(float cosThetaI, float cosThetaO, float sinThetaI, float sinThetaO, float v) {
  const float a = cosThetaI * cosThetaO / v, b = sinThetaI * sinThetaO / v;
  if (v <= 0.1f) return std::exp(logBesselI0(a) - b - 1 / v + 0.6931f + std::log(1 / (2 * v)));
  return std::exp(-b) * besselI0(a) / (std::sinh(1 / v) * 2 * v);
}

float logistic(float x, float s) {
  x = std::abs(x);
  return std::exp(-x / s) / (s * sqr(1 + std::exp(-x / s)));
}
float logisticCdf(float x, float s) {
  return 1 / (1 + std::exp(-x / s));
}
float trimmedLogistic(float x, float s, float a, float b) {
  return logistic(x, s) / (logisticCdf(b, s) - logisticCdf(a, s));
}
float sampleTrimmedLogistic(float u, float s, float a, float b) {
  const float k = logisticCdf(b, s) - logisticCdf(a, s);
  const float x = -s * std::log(1 / (u * k + logisticCdf(a, s)) - 1);
  return std::clamp(x, a, b);
}

float phiOf(int p, float gammaO, float gammaT) {
  return 2 * float(p) * gammaT - 2 * gammaO + float(p) * kPi;
}
// The azimuthal scattering function of lobe p.
float np(float phi, int p, float s, float gammaO, float gammaT) {
  float dphi = phi - phiOf(p, gammaO, gammaT);
  while (dphi > kPi) dphi -= 2 * kPi;
  while (dphi < -kPi) dphi += 2 * kPi;
  return trimmedLogistic(dphi, s, -kPi, kPi);
}

// The attenuation of each lobe: Fresnel at the first crossing, the
// transmittance T of each pass through the fibre, and what remains after p.
std::array<Vec3f, kPMax + 1> ap(float cosThetaO, float eta, float h, Vec3f transmittance) {
  std::array<Vec3f, kPMax + 1> a;
  const float cosGammaO = safeSqrt(1 - h * h);
  const float f = fresnelDielectric(cosThetaO * cosGammaO, eta);
  a[0] = Vec3f(f);
  a[1] = transmittance * sqr(1 - f);
  for (int p = 2; p < kPMax; ++p) a[p] = a[p - 1] * transmittance * f;
  const Vec3f tf = transmittance * f;
  a[kPMax] = {a[kPMax - 1].x * tf.x / (1 - tf.x), a[kPMax - 1].y * tf.y / (1 - tf.y),
              a[kPMax - 1].z * tf.z / (1 - tf.z)};
  return a;
}

// pbrt's way of making two numbers of one: its even and odd bits.
uint32_t compactBits(uint32_t x) {
  x &= 0x55555555;
  x = (x ^ (x >> 1)) & 0x33333333;
  x = (x ^ (x >> 2)) & 0x0f0f0f0f;
  x = (x ^ (x >> 4)) & 0x00ff00ff;
  x = (x ^ (x >> 8)) & 0x0000ffff;
  return x;
}
Vec2f demux(float f) {
  const uint64_t v = uint64_t(double(f) * double(1ull << 32));
  return {float(compactBits(uint32_t(v))) / float(1 << 16),
          float(compactBits(uint32_t(v >> 1))) / float(1 << 16)};
}

struct HairLobe {
  float h, eta, s;
  Vec3f sigmaA;
  float v[kPMax + 1];
  float sin2kAlpha[3], cos2kAlpha[3];

  // sin and cos of theta_o turned by the scales' tilt for lobe p.
  void tilted(int p, float sinThetaO, float cosThetaO, float& sinOp, float& cosOp) const {
    if (p == 0) {
      sinOp = sinThetaO * cos2kAlpha[1] - cosThetaO * sin2kAlpha[1];
      cosOp = cosThetaO * cos2kAlpha[1] + sinThetaO * sin2kAlpha[1];
    } else if (p == 1) {
      sinOp = sinThetaO * cos2kAlpha[0] + cosThetaO * sin2kAlpha[0];
      cosOp = cosThetaO * cos2kAlpha[0] - sinThetaO * sin2kAlpha[0];
    } else if (p == 2) {
      sinOp = sinThetaO * cos2kAlpha[2] + cosThetaO * sin2kAlpha[2];
      cosOp = cosThetaO * cos2kAlpha[2] - sinThetaO * sin2kAlpha[2];
    } else {
      sinOp = sinThetaO;
      cosOp = cosThetaO;
    }
    cosOp = std::abs(cosOp);
  }

  // gamma_t and the transmittance of one pass, for theta_o.
  void refracted(float sinThetaO, float cosThetaO, float& gammaT, Vec3f& transmittance) const {
    const float sinThetaT = sinThetaO / eta;
    const float cosThetaT = safeSqrt(1 - sqr(sinThetaT));
    const float etap = std::sqrt(eta * eta - sqr(sinThetaO)) / cosThetaO;
    const float sinGammaT = h / etap;
    const float cosGammaT = safeSqrt(1 - sqr(sinGammaT));
    gammaT = safeAsin(sinGammaT);
    transmittance = expOf(sigmaA * (-2 * cosGammaT / cosThetaT));
  }

  std::array<float, kPMax + 1> lobePdf(float sinThetaO, float cosThetaO) const {
    float gammaT;
    Vec3f transmittance;
    refracted(sinThetaO, cosThetaO, gammaT, transmittance);
    const std::array<Vec3f, kPMax + 1> a = ap(cosThetaO, eta, h, transmittance);
    float sum = 0;
    for (const Vec3f& x : a) sum += lobeLuminance(x);
    std::array<float, kPMax + 1> pdf;
    for (int p = 0; p <= kPMax; ++p) pdf[p] = sum > 0 ? lobeLuminance(a[p]) / sum : 0;
    return pdf;
  }

  // f |cos theta_i| (pbrt's f divided by |cos| there, times it here).
  Vec3f eval(Vec3f wo, Vec3f wi) const {
    if (wi.z == 0) return Vec3f(0);
    const float sinThetaO = wo.x, cosThetaO = safeSqrt(1 - sqr(sinThetaO));
    const float phiO = std::atan2(wo.z, wo.y);
    const float sinThetaI = wi.x, cosThetaI = safeSqrt(1 - sqr(sinThetaI));
    const float phiI = std::atan2(wi.z, wi.y);
    float gammaT;
    Vec3f transmittance;
    refracted(sinThetaO, cosThetaO, gammaT, transmittance);
    const float gammaO = safeAsin(h);
    const float phi = phiI - phiO;
    const std::array<Vec3f, kPMax + 1> a = ap(cosThetaO, eta, h, transmittance);
    Vec3f sum(0);
    for (int p = 0; p < kPMax; ++p) {
      float sinOp, cosOp;
      tilted(p, sinThetaO, cosThetaO, sinOp, cosOp);
      sum = sum +
            a[p] * (mp(cosThetaI, cosOp, sinThetaI, sinOp, v[p]) * np(phi, p, s, gammaO, gammaT));
    }
    sum = sum + a[kPMax] * (mp(cosThetaI, cosThetaO, sinThetaI, sinThetaO, v[kPMax]) / (2 * kPi));
    return isFinite(sum) ? sum : Vec3f(0);
  }

  float pdfOf(float sinThetaO, float cosThetaO, float sinThetaI, float cosThetaI, float dphi,
              const std::array<float, kPMax + 1>& lobes) const {
    float gammaT;
    Vec3f transmittance;
    refracted(sinThetaO, cosThetaO, gammaT, transmittance);
    const float gammaO = safeAsin(h);
    float pdf = 0;
    for (int p = 0; p < kPMax; ++p) {
      float sinOp, cosOp;
      tilted(p, sinThetaO, cosThetaO, sinOp, cosOp);
      pdf +=
          mp(cosThetaI, cosOp, sinThetaI, sinOp, v[p]) * lobes[p] * np(dphi, p, s, gammaO, gammaT);
    }
    pdf += mp(cosThetaI, cosThetaO, sinThetaI, sinThetaO, v[kPMax]) * lobes[kPMax] / (2 * kPi);
    return pdf;
  }

  float pdf(Vec3f wo, Vec3f wi) const {
    const float sinThetaO = wo.x, cosThetaO = safeSqrt(1 - sqr(sinThetaO));
    const float sinThetaI = wi.x, cosThetaI = safeSqrt(1 - sqr(sinThetaI));
    const float dphi = std::atan2(wi.z, wi.y) - std::atan2(wo.z, wo.y);
    const float p =
        pdfOf(sinThetaO, cosThetaO, sinThetaI, cosThetaI, dphi, lobePdf(sinThetaO, cosThetaO));
    return std::isfinite(p) ? p : 0;
  }

  // pbrt's sampling: a lobe by its attenuation, theta_i from its Mp, and
  // phi from its Np (the last lobe: uniformly).
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
    const float sinThetaO = wo.x, cosThetaO = safeSqrt(1 - sqr(sinThetaO));
    if (!(cosThetaO > 0)) return false;
    const float phiO = std::atan2(wo.z, wo.y);
    const std::array<float, kPMax + 1> lobes = lobePdf(sinThetaO, cosThetaO);
    int p = 0;
    for (; p < kPMax; ++p) {
      if (uLobe < lobes[p]) break;
      uLobe -= lobes[p];
    }
    float sinOp, cosOp;
    tilted(p, sinThetaO, cosThetaO, sinOp, cosOp);
    const Vec2f um = demux(u.x);
    const float u0 = std::max(um.x, 1e-5f);
    const float cosTheta = 1 + v[p] * std::log(u0 + (1 - u0) * std::exp(-2 / v[p]));
    const float sinTheta = safeSqrt(1 - sqr(cosTheta));
    const float cosPhi = std::cos(2 * kPi * um.y);
    const float sinThetaI = std::clamp(-cosTheta * sinOp + sinTheta * cosPhi * cosOp, -1.0f, 1.0f);
    const float cosThetaI = safeSqrt(1 - sqr(sinThetaI));
    float gammaT;
    Vec3f transmittance;
    refracted(sinThetaO, cosThetaO, gammaT, transmittance);
    const float gammaO = safeAsin(h);
    const float dphi = p < kPMax
                           ? phiOf(p, gammaO, gammaT) + sampleTrimmedLogistic(u.y, s, -kPi, kPi)
                           : 2 * kPi * u.y;
    const float phiI = phiO + dphi;
    out.wi = {sinThetaI, cosThetaI * std::cos(phiI), cosThetaI * std::sin(phiI)};
    out.pdf = pdfOf(sinThetaO, cosThetaO, sinThetaI, cosThetaI, dphi, lobes);
    if (!(out.pdf > 0) || !std::isfinite(out.pdf)) return false;
    out.weight = eval(wo, out.wi) * (1 / out.pdf);
    out.delta = false;
    return isFinite(out.weight);
  }
};

}  // namespace

Vec3f hairSigmaAFromMelanin(float eumelanin, float pheomelanin) {
  return Vec3f(0.419f, 0.697f, 1.37f) * eumelanin + Vec3f(0.187f, 0.4f, 1.05f) * pheomelanin;
}

Vec3f hairSigmaAFromColor(Vec3f color, float betaN) {
  const float b = betaN;
  const float d = 5.969f - 0.215f * b + 2.532f * b * b - 10.73f * b * b * b +
                  5.574f * b * b * b * b + 0.245f * b * b * b * b * b;
  auto one = [&](float c) { return sqr(std::log(std::clamp(c, 1e-6f, 1.0f)) / d); };
  return {one(color.x), one(color.y), one(color.z)};
}

Bsdf hairBsdf(float h, float eta, Vec3f sigmaA, float betaM, float betaN, float alphaDegrees) {
  static_assert(sizeof(HairLobe) <= Bsdf::kCapacity);
  HairLobe lobe;
  lobe.h = std::clamp(h, -1.0f, 1.0f);
  lobe.eta = eta;
  lobe.sigmaA = max(sigmaA, Vec3f(0));
  const float bm = std::clamp(betaM, 0.0f, 1.0f), bn = std::clamp(betaN, 0.0f, 1.0f);
  lobe.v[0] = sqr(0.726f * bm + 0.812f * bm * bm + 3.7f * std::pow(bm, 20.0f));
  lobe.v[1] = 0.25f * lobe.v[0];
  lobe.v[2] = 4 * lobe.v[0];
  for (int p = 3; p <= kPMax; ++p) lobe.v[p] = lobe.v[2];
  lobe.s = 0.626657069f * (0.265f * bn + 1.194f * bn * bn + 5.372f * std::pow(bn, 22.0f));
  lobe.sin2kAlpha[0] = std::sin(alphaDegrees * kPi / 180);
  lobe.cos2kAlpha[0] = safeSqrt(1 - sqr(lobe.sin2kAlpha[0]));
  for (int i = 1; i < 3; ++i) {
    lobe.sin2kAlpha[i] = 2 * lobe.cos2kAlpha[i - 1] * lobe.sin2kAlpha[i - 1];
    lobe.cos2kAlpha[i] = sqr(lobe.cos2kAlpha[i - 1]) - sqr(lobe.sin2kAlpha[i - 1]);
  }
  return Bsdf(lobe, false, true);
}

Vec3f HairModel::absorptionAt(Vec3f color) const {
  switch (absorption) {
    case Absorption::SigmaA:
      return sigmaA;
    case Absorption::Color:
      return hairSigmaAFromColor(color, betaN);
    case Absorption::Melanin:
      break;
  }
  return hairSigmaAFromMelanin(std::max(0.0f, eumelanin), std::max(0.0f, pheomelanin));
}

Bsdf HairModel::bsdf(Vec3f color, const MaterialResources& resources) const {
  return bsdfAt(color, {0, 0.5f}, resources);
}

Bsdf HairModel::bsdfAt(Vec3f color, Vec2f uv, const MaterialResources&) const {
  return hairBsdf(-1 + 2 * uv.y, eta, absorptionAt(color), betaM, betaN, alphaDegrees);
}

void HairModel::write(MaterialRecordWriter& record) const {
  record.pod(uint8_t(absorption));
  record.pod(sigmaA);
  record.pod(eumelanin);
  record.pod(pheomelanin);
  record.pod(eta);
  record.pod(betaM);
  record.pod(betaN);
  record.pod(alphaDegrees);
}

std::shared_ptr<const MaterialModel> HairModel::read(MaterialRecordReader& record) {
  auto m = std::make_shared<HairModel>();
  const auto absorption = record.pod<uint8_t>();
  if (absorption > uint8_t(Absorption::Color))
    record.fail(fmt::format("hair: unknown absorption {}", absorption));
  m->absorption = Absorption(absorption);
  m->sigmaA = record.pod<Vec3f>();
  m->eumelanin = record.pod<float>();
  m->pheomelanin = record.pod<float>();
  m->eta = record.pod<float>();
  m->betaM = record.pod<float>();
  m->betaN = record.pod<float>();
  m->alphaDegrees = record.pod<float>();
  return m;
}

std::string HairModel::describe() const {
  std::string what;
  switch (absorption) {
    case Absorption::SigmaA:
      what = fmt::format("sigma_a ({:g}, {:g}, {:g})", sigmaA.x, sigmaA.y, sigmaA.z);
      break;
    case Absorption::Melanin:
      what = fmt::format("eumelanin {:g}, pheomelanin {:g}", eumelanin, pheomelanin);
      break;
    case Absorption::Color:
      what = "sigma_a from the colour";
      break;
  }
  return fmt::format("hair ({}, eta {:g}, beta_m {:g}, beta_n {:g}, alpha {:g})", what, eta, betaM,
                     betaN, alphaDegrees);
}

}  // namespace ferry
