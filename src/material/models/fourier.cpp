#include "material/models/fourier.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/catmull_rom.h"
#include "material/models/diffuse.h"

namespace ferry {
namespace {

constexpr int32_t kMaxChannels = 3;

// Cosine of the azimuth between -wi (written `wiNeg`) and wo. Where wo has
// no azimuth (normal incidence) it is measured from +x, as the sampler
// measures it there; pbrt-v3 takes 1 and samples every direction along the
// normal, which no density describes.
float cosAzimuth(Vec3f wo, Vec3f wiNeg) {
  const float oxy = wo.x * wo.x + wo.y * wo.y, ixy = wiNeg.x * wiNeg.x + wiNeg.y * wiNeg.y;
  if (ixy == 0) return 1;
  if (oxy == 0) return std::clamp(wiNeg.x / std::sqrt(ixy), -1.0f, 1.0f);
  return std::clamp((wo.x * wiNeg.x + wo.y * wiNeg.y) / std::sqrt(oxy * ixy), -1.0f, 1.0f);
}

// pbrt-v3's scale for radiance transport: radiance crossing the interface
// (mu_i mu_o > 0) is scaled by (eta_to / eta_from)^2.
float transportScale(const FourierBsdfTable& t, float muI, float muO) {
  if (!(muI * muO > 0)) return 1;
  const float e = muI > 0 ? 1 / t.eta : t.eta;
  return e * e;
}

// The 16 entries around (muI, muO) summed with their spline weights into ak
// (channel c from c * t.mMax); returns the longest series, -1 outside the
// table. weightsO and offsetO are mu_o's, for the cdf.
int32_t interpolate(const FourierBsdfTable& t, float muI, float muO, int32_t channels, float* ak,
                    int32_t& offsetO, float weightsO[4]) {
  int32_t offsetI;
  float weightsI[4];
  if (!catmullRomWeights(t.mu.data(), t.nMu, muI, offsetI, weightsI) ||
      !catmullRomWeights(t.mu.data(), t.nMu, muO, offsetO, weightsO))
    return -1;
  // The entries with a weight, then each channel summed over them in the
  // same order (zeros past the longest series are never read).
  const float* series[16];
  float weights[16];
  int32_t orders[16];
  int32_t n = 0, longest = 0;
  for (int32_t b = 0; b < 4; ++b)
    for (int32_t a = 0; a < 4; ++a) {
      // (A zero weight marks a node beyond the grid's end.)
      const float weight = weightsI[a] * weightsO[b];
      if (weight == 0) continue;
      series[n] = t.coefficientsAt(offsetI + a, offsetO + b, orders[n]);
      weights[n] = weight;
      longest = std::max(longest, orders[n]);
      ++n;
    }
  for (int32_t c = 0; c < channels; ++c) {
    float* __restrict out = ak + c * t.mMax;
    std::fill(out, out + longest, 0.0f);
    for (int32_t j = 0; j < n; ++j) {
      const int32_t m = orders[j];
      const float* __restrict in = series[j] + c * m;
      const float weight = weights[j];
      for (int32_t k = 0; k < m; ++k) out[k] += weight * in[k];
    }
  }
  return longest;
}

// 2 pi times the luminance's integral over the sphere of directions wi at
// mu_o: the normalisation of the sampling density.
float sampledIntegral(const FourierBsdfTable& t, int32_t offsetO, const float weightsO[4]) {
  float rho = 0;
  for (int32_t o = 0; o < 4; ++o)
    if (weightsO[o] != 0)
      rho += weightsO[o] * t.cdf[size_t(offsetO + o) * size_t(t.nMu) + size_t(t.nMu - 1)];
  return rho * (2 * kPi);
}

// f |cos(wi)| from the interpolated series at cos(phi) (luminance y, given).
Vec3f value(const FourierBsdfTable& t, const float* ak, int32_t m, float y, float cosPhi,
            float scale) {
  y = std::max(0.0f, y);
  if (t.nChannels == 1) return Vec3f(y * scale);
  const float r = fourier::series(ak + t.mMax, m, cosPhi);
  const float b = fourier::series(ak + 2 * t.mMax, m, cosPhi);
  // pbrt-v3's green from luminance, red and blue.
  const float g = 1.39829f * y - 0.100913f * b - 0.297375f * r;
  return max(Vec3f(r, g, b) * scale, Vec3f(0));
}

// mu_i with density proportional to the spline of a0 over mu_i at mu_o
// (pbrt-v3's SampleCatmullRom2D over the table's cdf).
bool sampleMuI(const FourierBsdfTable& t, float muO, float u, float& muI) {
  return sampleCatmullRom2D(t.mu.data(), t.nMu, t.mu.data(), t.nMu, t.a0.data(), t.cdf.data(), muO,
                            u, muI);
}

// phi in [0, 2 pi) with density proportional to the series (pbrt-v3's
// SampleFourier: half the numbers for [0, pi], mirrored for the rest, since
// the series is even); returns the series at phi.
float sampleAzimuth(const float* ak, const float* recip, int32_t m, float u, double& phiOut) {
  const bool mirror = u >= 0.5f;
  u = mirror ? 1 - 2 * (u - 0.5f) : 2 * u;
  double lo = 0, hi = kPi, phi = 0.5 * kPi, F = 0, f = 0;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double cosPhi = std::cos(phi), sinPhi = std::sqrt(std::max(0.0, 1 - cosPhi * cosPhi));
    // cos(k phi) and sin(k phi) by Chebyshev's recurrence.
    double cosPrev = cosPhi, cosCur = 1, sinPrev = -sinPhi, sinCur = 0;
    F = ak[0] * phi;
    f = ak[0];
    for (int32_t k = 1; k < m; ++k) {
      const double sinNext = 2 * cosPhi * sinCur - sinPrev;
      const double cosNext = 2 * cosPhi * cosCur - cosPrev;
      sinPrev = sinCur;
      sinCur = sinNext;
      cosPrev = cosCur;
      cosCur = cosNext;
      F += ak[k] * recip[k] * sinNext;
      f += ak[k] * cosNext;
    }
    F -= u * ak[0] * kPi;
    if (F > 0)
      hi = phi;
    else
      lo = phi;
    if (std::abs(F) < 1e-6 || hi - lo < 1e-6) break;
    phi -= F / f;
    if (!(phi > lo && phi < hi)) phi = 0.5 * (lo + hi);
  }
  phiOut = mirror ? 2 * kPi - phi : phi;
  return float(f);
}

}  // namespace

namespace fourier {

float series(const float* a, int32_t m, double cosPhi) {
  double sum = 0, cosPrev = cosPhi, cosCur = 1;
  for (int32_t k = 0; k < m; ++k) {
    sum += a[k] * cosCur;
    const double cosNext = 2 * cosPhi * cosCur - cosPrev;
    cosPrev = cosCur;
    cosCur = cosNext;
  }
  return float(sum);
}

}  // namespace fourier

Vec3f fourierEval(const FourierBsdfTable& t, Vec3f wo, Vec3f wi) {
  if (wi.z == 0) return Vec3f(0);
  float pdf;
  return fourierEvalPdf(t, wo, wi, pdf);
}

Vec3f fourierEvalPdf(const FourierBsdfTable& t, Vec3f wo, Vec3f wi, float& pdf) {
  const float muI = -wi.z, muO = wo.z;
  pdf = 0;
  float ak[kMaxChannels * FourierBsdfTable::kMaxOrder];
  int32_t offsetO;
  float weightsO[4];
  // Channel 0 of the interpolated series is what fourierPdf interpolates.
  const int32_t m = interpolate(t, muI, muO, t.nChannels, ak, offsetO, weightsO);
  if (m < 0) return Vec3f(0);
  const float cosPhi = cosAzimuth(wo, -wi);
  const float y = fourier::series(ak, m, cosPhi);
  const float rho = sampledIntegral(t, offsetO, weightsO);
  pdf = rho > 0 && y > 0 ? y / rho : 0;
  if (muI == 0) return Vec3f(0);
  // f = series / |mu_i|: times |cos(wi)| = |mu_i| leaves the series.
  return value(t, ak, m, y, cosPhi, transportScale(t, muI, muO));
}

float fourierPdf(const FourierBsdfTable& t, Vec3f wo, Vec3f wi) {
  const float muI = -wi.z, muO = wo.z;
  float ak[FourierBsdfTable::kMaxOrder];
  int32_t offsetO;
  float weightsO[4];
  const int32_t m = interpolate(t, muI, muO, 1, ak, offsetO, weightsO);
  if (m < 0) return 0;
  const float rho = sampledIntegral(t, offsetO, weightsO);
  const float y = fourier::series(ak, m, cosAzimuth(wo, -wi));
  return rho > 0 && y > 0 ? y / rho : 0;
}

bool fourierSample(const FourierBsdfTable& t, Vec3f wo, Vec2f u, BsdfSample& out) {
  const float muO = wo.z;
  float muI;
  if (!sampleMuI(t, muO, u.y, muI)) return false;
  // The azimuth follows the luminance alone; the value is taken below, at
  // the direction produced.
  float ak[FourierBsdfTable::kMaxOrder];
  int32_t offsetO;
  float weightsO[4];
  const int32_t m = interpolate(t, muI, muO, 1, ak, offsetO, weightsO);
  if (m < 0) return false;
  const float rho = sampledIntegral(t, offsetO, weightsO);
  double phi;
  const float y = sampleAzimuth(ak, t.recip.data(), m, u.x, phi);
  if (!(y > 0 && rho > 0)) return false;
  // -wi: wo's azimuth turned by phi, at elevation mu_i (from +x where wo
  // has no azimuth, as cosAzimuth measures it).
  const float oxy = std::sqrt(wo.x * wo.x + wo.y * wo.y);
  const float dx = oxy > 0 ? wo.x / oxy : 1, dy = oxy > 0 ? wo.y / oxy : 0;
  const float sinI = std::sqrt(std::max(0.0f, 1 - muI * muI));
  const float c = float(std::cos(phi)), s = float(std::sin(phi));
  // Normalised again: rounding would otherwise compound over bounces (pbrt-v3 does too).
  out.wi = -normalize(Vec3f(sinI * (c * dx - s * dy), sinI * (s * dx + c * dy), muI));
  out.delta = false;
  // The density Y / rho is what fourierPdf gives for this wi; taken from the
  // direction actually produced, so that MIS and the weight agree with it.
  const Vec3f f = fourierEvalPdf(t, wo, out.wi, out.pdf);
  if (!(out.pdf > 0)) return false;
  out.weight = f * (1 / out.pdf);
  return true;
}

namespace {

struct FourierLobe {
  const FourierBsdfTable* table;
  Vec3f eval(Vec3f wo, Vec3f wi) const { return fourierEval(*table, wo, wi); }
  float pdf(Vec3f wo, Vec3f wi) const { return fourierPdf(*table, wo, wi); }
  Vec3f evalPdf(Vec3f wo, Vec3f wi, float& pdf) const {
    return fourierEvalPdf(*table, wo, wi, pdf);
  }
  bool sample(Vec3f wo, float, Vec2f u, BsdfSample& out) const {
    return fourierSample(*table, wo, u, out);
  }
};

}  // namespace

Bsdf fourierBsdf(const FourierBsdfTable& table) {
  // A table whose sides differ is shaded on the side the ray arrives on in
  // the shading normal's frame, as a transmitting one is (Bsdf's `transmits`).
  return Bsdf(FourierLobe{&table}, false, table.sided());
}

Bsdf FourierModel::bsdf(Vec3f color, const MaterialResources& resources) const {
  const FourierBsdfTable* t = table >= 0 && size_t(table) < resources.bsdfTables.size()
                                  ? resources.bsdfTables[size_t(table)].get()
                                  : nullptr;
  return t ? fourierBsdf(*t) : diffuseBsdf(color);
}

std::shared_ptr<const MaterialModel> FourierModel::read(MaterialRecordReader& record) {
  return std::make_shared<FourierModel>(record.table());
}

std::string FourierModel::describe() const {
  return fmt::format("fourier (table {})", table);
}

}  // namespace ferry
