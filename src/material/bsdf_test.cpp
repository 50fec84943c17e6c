// BSDF tests in the style of pbrt's and Mitsuba's: every lobe, several
// incident directions (normal, oblique, grazing, and from inside for
// dielectrics), checked for
//  - sampling matching the pdf: chi-square goodness of fit of sample()'s
//    directions against pdf() integrated over (theta, phi) cells, low cells
//    pooled, failed samples as one more cell (so pdf() must also integrate to
//    the probability that sample() succeeds); significance 0.01 with a Sidak
//    correction over all cases;
//  - energy: the Monte Carlo albedo E[weight] is at most 1 (one-sided z-test);
//  - consistency: weight == eval / pdf and pdf == pdf() at sampled directions,
//    and the albedo from quadrature of eval() equals the Monte Carlo one (so no
//    energy sits where sample() never goes);
//  - reciprocity, and fresnelDielectric against closed forms.
#include "material/bsdf.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "io/pbrt/fourier_bsdf_file.h"
#include "material/models/coated_conductor.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"
#include "material/models/diffuse_transmission.h"
#include "material/models/fourier.h"
#include "material/models/fresnel_blend.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using testing::MeanVariance;
using testing::TestRng;

constexpr double kAlpha = 0.01;  // family-wise significance of each group of tests

Vec3f direction(float thetaDegrees, float phi = 0.7f) {
  float t = thetaDegrees * kPi / 180;
  return {std::sin(t) * std::cos(phi), std::sin(t) * std::sin(phi), std::cos(t)};
}

struct LobeCase {
  std::string name;
  Bsdf bsdf;
  Vec3f wo;
};

std::string degrees(float d) {
  return std::to_string(int(std::lround(d)));
}

// A tabulated (Fourier) BSDF made here, so that transmission is tested too
// (the one real table at hand, paint.bsdf, only reflects): on a grid with 0
// twice (as layerlab's), a0 = albedo |mu_i| / pi on each side that is asked
// for (a Lambertian reflector or window, albedo = each side's share), an
// azimuthal term a1 = a0 sin(theta_i) sin(theta_o) / 2 (the series stays
// positive), and the cdf as the spline's integral, as layerlab writes it.
std::unique_ptr<FourierBsdfTable> syntheticTable(float eta, float reflect, float transmit) {
  auto t = std::make_unique<FourierBsdfTable>();
  t->name = "synthetic";
  const int32_t half = 12, n = 2 * half + 2;
  for (int32_t k = 0; k <= half; ++k) t->mu.push_back(-1 + float(k) / half);
  for (int32_t k = 0; k <= half; ++k) t->mu.push_back(float(k) / half);
  t->nMu = n;
  t->nChannels = 1;
  t->mMax = 2;
  t->eta = eta;
  for (int32_t o = 0; o < n; ++o)
    for (int32_t i = 0; i < n; ++i) {
      const float muI = t->mu[i], muO = t->mu[o];
      // (mu_i = cos(-wi): opposite signs reflect.)
      const float share = muI * muO < 0 ? reflect : muI * muO > 0 ? transmit : 0;
      const float a0 = share * std::abs(muI) / kPi;
      const float a1 =
          0.5f * a0 * std::sqrt(std::max(0.0f, 1 - muI * muI) * std::max(0.0f, 1 - muO * muO));
      t->offset.push_back(uint32_t(t->coefficients.size()));
      t->order.push_back(2);
      t->coefficients.push_back(a0);
      t->coefficients.push_back(a1);
    }
  t->cdf.assign(size_t(n) * n, 0);
  for (int32_t o = 0; o < n; ++o) {
    auto f = [&](int32_t i) { return t->coefficients[t->offset[t->entry(i, o)]]; };
    const std::vector<float>& x = t->mu;
    double sum = 0;
    for (int32_t i = 0; i + 1 < n; ++i) {
      const float width = x[i + 1] - x[i], f0 = f(i), f1 = f(i + 1);
      const float d0 = i > 0 ? width * (f1 - f(i - 1)) / (x[i + 1] - x[i - 1]) : f1 - f0;
      const float d1 = i + 2 < n ? width * (f(i + 2) - f0) / (x[i + 2] - x[i]) : f1 - f0;
      sum += ((d0 - d1) / 12 + (f0 + f1) / 2) * width;
      t->cdf[size_t(o) * n + size_t(i + 1)] = float(sum);
    }
  }
  EXPECT_EQ(t->finish(), "");
  return t;
}

// The tables the Fourier cases point to (they outlive every Bsdf).
const FourierBsdfTable* paintTable() {
  static const std::shared_ptr<const FourierBsdfTable> paint = [] {
    const std::filesystem::path path =
        std::filesystem::path(FERRY_SHARED_SCENES) / "breakfast" / "bsdfs" / "paint.bsdf";
    return std::filesystem::exists(path) ? readFourierBsdfFile(path.string()) : nullptr;
  }();
  return paint.get();
}
const FourierBsdfTable& windowTable() {
  static const std::unique_ptr<FourierBsdfTable> t = syntheticTable(1, 0.45f, 0.45f);
  return *t;
}
const FourierBsdfTable& glassTable() {
  static const std::unique_ptr<FourierBsdfTable> t = syntheticTable(1.5f, 0.3f, 0.6f);
  return *t;
}

// Every non-delta lobe at several incident directions.
std::vector<LobeCase> roughCases() {
  std::vector<LobeCase> cases;
  const float outside[] = {0, 30, 60, 85};
  for (float t : outside)
    cases.push_back({"diffuse_wo" + degrees(t), diffuseBsdf(Vec3f(1)), direction(t)});
  for (float t : outside)
    cases.push_back({"orennayar_s30_wo" + degrees(t), diffuseBsdf(Vec3f(1), 30), direction(t)});
  // Diffuse transmission, from either side (its normals are kept).
  for (float t : {0.0f, 45.0f, 85.0f, 120.0f, 175.0f}) {
    cases.push_back({"transmission_r5t5_wo" + degrees(t),
                     diffuseTransmissionBsdf(Vec3f(0.5f), Vec3f(0.5f)), direction(t)});
    cases.push_back({"transmission_r2t7_wo" + degrees(t),
                     diffuseTransmissionBsdf(Vec3f(0.2f), Vec3f(0.7f)), direction(t)});
  }
  // Coats: pbrt-v3's plastic (additive, seen from inside the glass: eta 1 /
  // 1.5) with half-white base and coat, so that the sum stays below one; and
  // layered coats over a white base. (Roughness from 0.3: the quadrature
  // grid cannot resolve narrower lobes at normal incidence.)
  for (float r : {0.3f, 0.6f})
    for (float t : outside) {
      const std::string rough = std::to_string(int(r * 10));
      cases.push_back({"plastic_r" + rough + "_wo" + degrees(t),
                       coatedBsdf(Vec3f(0.5f), Vec3f(0.5f), r, 1 / 1.5f, false), direction(t)});
      cases.push_back({"layered_r" + rough + "_wo" + degrees(t),
                       coatedBsdf(Vec3f(1), Vec3f(1), r, 1.5f, true, 20), direction(t)});
      cases.push_back({"coatedmetal_r" + rough + "_wo" + degrees(t),
                       coatedConductorBsdf(Vec3f(1), 0.5f, Vec3f(1), r, 1.5f), direction(t)});
      cases.push_back({"fresnelblend_r" + rough + "_wo" + degrees(t),
                       fresnelBlendBsdf(Vec3f(1), Vec3f(0.3f), r), direction(t)});
    }
  for (float r : {0.2f, 0.5f, 1.0f})
    for (float t : outside)
      cases.push_back({"conductor_r" + std::to_string(int(r * 10)) + "_wo" + degrees(t),
                       conductorBsdf(Vec3f(1), r), direction(t)});
  // Dielectrics: from the outside (wo.z > 0) and the inside (wo.z < 0), with
  // the ior as seen from +z both above and below 1.
  const float dielectricAngles[] = {5, 45, 85, 120, 175};
  for (float ior : {1.5f, 1 / 1.5f})
    for (float r : {0.3f, 0.7f})
      for (float t : dielectricAngles)
        cases.push_back({std::string("dielectric_") + (ior > 1 ? "ior1.5" : "ior0.67") + "_r" +
                             std::to_string(int(r * 10)) + "_wo" + degrees(t),
                         dielectricBsdf(ior, r), direction(t)});
  // Tabulated BSDFs: pbrt-v3's paint (three channels, reflection only; when
  // ../shared is there), a window (eta 1) from both sides, and an eta 1.5
  // interface from above (from below, pbrt-v3's eta^2 for radiance
  // transport rightly returns more than 1).
  // (At 85 degrees paint's series dips below zero: BsdfFourier below.)
  if (const FourierBsdfTable* paint = paintTable())
    for (float t : {0.0f, 30.0f, 60.0f, 75.0f})
      cases.push_back({"fourier_paint_wo" + degrees(t), fourierBsdf(*paint), direction(t)});
  for (float t : dielectricAngles)
    cases.push_back({"fourier_window_wo" + degrees(t), fourierBsdf(windowTable()), direction(t)});
  for (float t : outside)
    cases.push_back({"fourier_eta1.5_wo" + degrees(t), fourierBsdf(glassTable()), direction(t)});
  return cases;
}

// ------------------------------------------------------------ quadrature grid

// The sphere in (theta, phi) cells; Mitsuba's layout (theta, not cos theta,
// resolves the narrow lobes near the poles).
constexpr int kThetaBins = 90;
constexpr int kPhiBins = 180;
constexpr int kCells = kThetaBins * kPhiBins;

int cellOf(Vec3f w) {
  float z = std::clamp(w.z / length(w), -1.0f, 1.0f);
  float theta = std::acos(z);
  float phi = std::atan2(w.y, w.x);
  if (phi < 0) phi += 2 * kPi;
  int i = std::min(int(theta / kPi * kThetaBins), kThetaBins - 1);
  int j = std::min(int(phi / (2 * kPi) * kPhiBins), kPhiBins - 1);
  return i * kPhiBins + j;
}

// Integrals of pdf(wo, .) and of eval(wo, .) (max channel) over a
// (theta, phi) rectangle, dw = sin(theta) dtheta dphi.
struct CellIntegral {
  double pdf = 0, eval = 0;
};

// 3-point Gauss-Legendre per dimension.
CellIntegral gauss3(const Bsdf& bsdf, Vec3f wo, double t0, double t1, double p0, double p1) {
  static constexpr double x[3] = {-0.7745966692414834, 0, 0.7745966692414834};
  static constexpr double w[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};
  CellIntegral r;
  for (int a = 0; a < 3; ++a) {
    double theta = 0.5 * (t0 + t1) + 0.5 * (t1 - t0) * x[a];
    double st = std::sin(theta), ct = std::cos(theta);
    for (int b = 0; b < 3; ++b) {
      double phi = 0.5 * (p0 + p1) + 0.5 * (p1 - p0) * x[b];
      Vec3f wi{float(st * std::cos(phi)), float(st * std::sin(phi)), float(ct)};
      double weight = w[a] * w[b] * st;
      r.pdf += weight * bsdf.pdf(wo, wi);
      r.eval += weight * maxComponent(bsdf.eval(wo, wi));
    }
  }
  double scale = 0.25 * (t1 - t0) * (p1 - p0);
  r.pdf *= scale;
  r.eval *= scale;
  return r;
}

// Adaptive quadrature: split in four until the four children agree with
// their parent to `tolerance` (absolute) or 1e-5 relative; with a million
// samples that is far below a cell's counting noise. `errorBound` collects |children - parent| of
// the accepted splits, a (very) conservative bound on the error of the result.
CellIntegral integrateAdaptive(const Bsdf& bsdf, Vec3f wo, double t0, double t1, double p0,
                               double p1, const CellIntegral& whole, double tolerance, int depth,
                               double& errorBound) {
  double tm = 0.5 * (t0 + t1), pm = 0.5 * (p0 + p1);
  CellIntegral q[4] = {gauss3(bsdf, wo, t0, tm, p0, pm), gauss3(bsdf, wo, tm, t1, p0, pm),
                       gauss3(bsdf, wo, t0, tm, pm, p1), gauss3(bsdf, wo, tm, t1, pm, p1)};
  CellIntegral sum;
  for (const CellIntegral& c : q) {
    sum.pdf += c.pdf;
    sum.eval += c.eval;
  }
  double diff = std::max(std::abs(sum.pdf - whole.pdf), std::abs(sum.eval - whole.eval));
  double size = std::max(std::abs(sum.pdf), std::abs(sum.eval));
  if (diff <= std::max(tolerance, 1e-5 * size) || depth >= 7) {
    errorBound += diff;
    return sum;
  }
  CellIntegral r;
  const double rect[4][4] = {
      {t0, tm, p0, pm}, {tm, t1, p0, pm}, {t0, tm, pm, p1}, {tm, t1, pm, p1}};
  for (int k = 0; k < 4; ++k) {
    CellIntegral c = integrateAdaptive(bsdf, wo, rect[k][0], rect[k][1], rect[k][2], rect[k][3],
                                       q[k], tolerance / 2, depth + 1, errorBound);
    r.pdf += c.pdf;
    r.eval += c.eval;
  }
  return r;
}

// Per-cell integrals of pdf() and eval() over the whole sphere.
void integrateCells(const Bsdf& bsdf, Vec3f wo, std::vector<double>& pdfIntegral,
                    std::vector<double>& evalIntegral, double& errorBound) {
  pdfIntegral.assign(kCells, 0);
  evalIntegral.assign(kCells, 0);
  errorBound = 0;
  const double dTheta = std::numbers::pi / kThetaBins, dPhi = 2 * std::numbers::pi / kPhiBins;
  for (int i = 0; i < kThetaBins; ++i) {
    for (int j = 0; j < kPhiBins; ++j) {
      double t0 = i * dTheta, t1 = (i + 1) * dTheta, p0 = j * dPhi, p1 = (j + 1) * dPhi;
      CellIntegral c = integrateAdaptive(bsdf, wo, t0, t1, p0, p1, gauss3(bsdf, wo, t0, t1, p0, p1),
                                         1e-8, 0, errorBound);
      pdfIntegral[i * kPhiBins + j] = c.pdf;
      evalIntegral[i * kPhiBins + j] = c.eval;
    }
  }
}

struct ChiSquareResult {
  double chi2 = 0;
  int dof = 0;
  double pValue = 1;
  std::string error;  // a sample where the pdf is zero
};

// Pearson's test with cells of expected count < 5 pooled (pbrt, Mitsuba).
// `expected` and `observed` include the failure cell.
ChiSquareResult chiSquare(const std::vector<double>& expected,
                          const std::vector<double>& observed) {
  ChiSquareResult r;
  std::vector<size_t> order(expected.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  double pooledExpected = 0, pooledObserved = 0;
  int cells = 0;
  for (size_t k : order) {
    if (expected[k] <= 0) {
      if (observed[k] > 0) {
        r.error = "a sample fell in cell " + std::to_string(k) + " where the pdf integrates to 0";
        r.pValue = 0;
        return r;
      }
      continue;
    }
    if (expected[k] < 5) {
      pooledExpected += expected[k];
      pooledObserved += observed[k];
      continue;
    }
    double d = observed[k] - expected[k];
    r.chi2 += d * d / expected[k];
    ++cells;
  }
  if (pooledExpected > 0) {
    double d = pooledObserved - pooledExpected;
    r.chi2 += d * d / pooledExpected;
    ++cells;
  }
  r.dof = cells - 1;
  r.pValue = testing::chiSquareSurvival(r.chi2, r.dof);
  return r;
}

class BsdfLobeTest : public ::testing::TestWithParam<LobeCase> {};

// What one pass of sampling measures.
struct SampleStatistics {
  std::vector<double> histogram = std::vector<double>(kCells + 1, 0);  // last: failures
  MeanVariance albedo;  // E[max channel of weight], failures counting 0
  int inconsistent = 0;
  std::string firstInconsistency;
};

constexpr int kSamples = 1000000;

SampleStatistics sampleLobe(const Bsdf& bsdf, Vec3f wo, uint64_t seed) {
  SampleStatistics s;
  TestRng rng(seed);
  for (int n = 0; n < kSamples; ++n) {
    float uLobe = rng.uniform();
    Vec2f u{rng.uniform(), rng.uniform()};
    BsdfSample bs;
    if (!bsdf.sample(wo, uLobe, u, bs)) {
      s.histogram[kCells] += 1;
      s.albedo.add(0);
      continue;
    }
    s.histogram[cellOf(bs.wi)] += 1;
    s.albedo.add(maxComponent(bs.weight));
    // weight == eval / pdf and pdf == pdf() at the sampled direction.
    float p = bsdf.pdf(wo, bs.wi);
    Vec3f f = bsdf.eval(wo, bs.wi);
    bool ok = !bs.delta && p > 0 && std::abs(bs.pdf - p) <= 1e-3f * p + 1e-6f &&
              std::abs(bs.weight.x - f.x / p) <= 1e-3f * bs.weight.x + 1e-6f &&
              std::abs(std::abs(length(bs.wi)) - 1) < 1e-4f;
    if (!ok && s.inconsistent++ == 0)
      s.firstInconsistency = "wi=(" + std::to_string(bs.wi.x) + "," + std::to_string(bs.wi.y) +
                             "," + std::to_string(bs.wi.z) + ") sample pdf " +
                             std::to_string(bs.pdf) + " pdf() " + std::to_string(p) + " weight " +
                             std::to_string(bs.weight.x) + " eval/pdf " + std::to_string(f.x / p);
  }
  return s;
}

TEST_P(BsdfLobeTest, SamplingMatchesPdfEnergyAndEval) {
  const LobeCase& c = GetParam();
  const double tests = double(roughCases().size());
  const double alphaChi = testing::sidak(kAlpha, tests);

  std::vector<double> pdfCells, evalCells;
  double quadratureError = 0;
  integrateCells(c.bsdf, c.wo, pdfCells, evalCells, quadratureError);
  double pdfTotal = 0, albedoQuadrature = 0;
  for (int k = 0; k < kCells; ++k) {
    pdfTotal += pdfCells[k];
    albedoQuadrature += evalCells[k];
  }

  SampleStatistics s = sampleLobe(c.bsdf, c.wo, std::hash<std::string>{}(c.name));

  // Sampling matches pdf().
  std::vector<double> expected(kCells + 1);
  for (int k = 0; k < kCells; ++k) expected[k] = pdfCells[k] * kSamples;
  expected[kCells] = std::max(0.0, 1 - pdfTotal) * kSamples;
  ChiSquareResult chi = chiSquare(expected, s.histogram);
  std::printf(
      "[ chi2     ] %-32s chi2 %9.1f dof %5d p %.4f (threshold %.2e)  pdf integral %.5f  fail "
      "%.4f\n",
      c.name.c_str(), chi.chi2, chi.dof, chi.pValue, alphaChi, pdfTotal,
      s.histogram[kCells] / kSamples);
  EXPECT_TRUE(chi.error.empty()) << chi.error;
  EXPECT_GT(chi.pValue, alphaChi) << c.name << ": sample() does not follow pdf(): chi2 " << chi.chi2
                                  << " with " << chi.dof << " dof";
  // pdf() cannot integrate to more than one.
  // pdf() cannot integrate to more than one (up to the quadrature's error).
  EXPECT_LE(pdfTotal, 1 + quadratureError) << c.name;

  // Consistency of sample() with eval() and pdf().
  EXPECT_EQ(s.inconsistent, 0) << c.name << ": first: " << s.firstInconsistency;

  // Energy: E[weight] <= 1 (white lobes), one-sided at the Sidak-corrected level.
  const double zOne = testing::oneSidedNormalQuantile(alphaChi);
  const double zTwo = testing::twoSidedNormalQuantile(alphaChi);
  std::printf("[ albedo   ] %-32s MC %.5f +- %.5f  quadrature of eval %.5f (error bound %.1e)\n",
              c.name.c_str(), s.albedo.mean, s.albedo.standardError(), albedoQuadrature,
              quadratureError);
  EXPECT_LE(s.albedo.mean, 1 + zOne * s.albedo.standardError() + 1e-6) << c.name;
  // All of eval()'s energy is reachable by sample(): the quadrature of eval
  // equals the Monte Carlo mean of the weights (to the statistical error, the
  // quadrature's error bound, and float evaluation of eval(), ~1e-6).
  EXPECT_NEAR(s.albedo.mean, albedoQuadrature,
              zTwo * s.albedo.standardError() + quadratureError + 1e-6)
      << c.name;
}

// evalPdf gives eval and pdf bit for bit, with or without the density
// (a tabulated BSDF computes both from one interpolation), at directions
// on both sides.
TEST_P(BsdfLobeTest, EvalPdfIsEvalAndPdf) {
  const LobeCase& c = GetParam();
  TestRng rng(7);
  for (int n = 0; n < 2000; ++n) {
    const float z = 2 * rng.uniform() - 1, phi = 2 * kPi * rng.uniform();
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    const Vec3f wi{r * std::cos(phi), r * std::sin(phi), z};
    float pdf = -1;
    const Vec3f both = c.bsdf.evalPdf(c.wo, wi, &pdf);
    const Vec3f alone = c.bsdf.evalPdf(c.wo, wi, nullptr);
    const Vec3f f = c.bsdf.eval(c.wo, wi);
    const float p = c.bsdf.pdf(c.wo, wi);
    ASSERT_EQ(std::memcmp(&both, &f, sizeof f), 0) << c.name << " n " << n;
    ASSERT_EQ(std::memcmp(&alone, &f, sizeof f), 0) << c.name << " n " << n;
    ASSERT_EQ(std::memcmp(&pdf, &p, sizeof p), 0) << c.name << " n " << n;
  }
}

// Where a table's series dips below zero (paint at grazing incidence: the
// truncated series rings), pbrt-v3's f and Pdf clamp it at zero, but its
// sampler inverts the unclamped series: the directions whose series is
// negative are dropped (failed samples) and pdf() integrates to a little
// more than one. Ferry keeps pbrt-v3's method; this bounds what it costs.
TEST(BsdfFourier, PaintAtGrazingIncidenceLosesOnlyItsNegativeLobes) {
  const FourierBsdfTable* paint = paintTable();
  if (!paint) GTEST_SKIP() << "paint.bsdf is not available";
  const Bsdf bsdf = fourierBsdf(*paint);
  const Vec3f wo = direction(85);
  std::vector<double> pdfCells, evalCells;
  double quadratureError = 0;
  integrateCells(bsdf, wo, pdfCells, evalCells, quadratureError);
  double pdfTotal = 0, albedoQuadrature = 0;
  for (int k = 0; k < kCells; ++k) {
    pdfTotal += pdfCells[k];
    albedoQuadrature += evalCells[k];
  }
  const SampleStatistics s = sampleLobe(bsdf, wo, 85);
  const double failed = s.histogram[kCells] / kSamples;
  std::printf(
      "[ fourier  ] paint at 85 degrees: pdf integral %.6f, failed samples %.6f, albedo MC "
      "%.5f quadrature %.5f\n",
      pdfTotal, failed, s.albedo.mean, albedoQuadrature);
  EXPECT_LT(pdfTotal, 1 + 2e-4);
  EXPECT_LT(failed, 2e-4);
  EXPECT_EQ(s.inconsistent, 0) << s.firstInconsistency;
  EXPECT_LE(s.albedo.mean, 1.0);
  EXPECT_NEAR(s.albedo.mean, albedoQuadrature, 2e-4);
}

INSTANTIATE_TEST_SUITE_P(BsdfLobes, BsdfLobeTest, ::testing::ValuesIn(roughCases()),
                         [](const ::testing::TestParamInfo<LobeCase>& info) {
                           std::string n = info.param.name;
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

// ------------------------------------------------------------------ delta lobes

// The frame buffer relies on this (frame_buffer.h): a sample is delta exactly
// when its lobe is, so a path that counts emission after a delta bounce never
// has a shadow ray in the same wavefront.
TEST(BsdfDelta, ASampleIsDeltaExactlyWhenItsLobeIs) {
  const Bsdf lobes[] = {diffuseBsdf(Vec3f(0.5f)), conductorBsdf(Vec3f(0.9f), 0),
                        conductorBsdf(Vec3f(0.9f), 0.3f), dielectricBsdf(1.5f, 0),
                        dielectricBsdf(1.5f, 0.3f)};
  for (const Bsdf& b : lobes) {
    for (float t : {10.0f, 60.0f, 120.0f, 170.0f}) {
      for (float uLobe : {0.01f, 0.5f, 0.99f}) {
        BsdfSample bs;
        if (b.sample(direction(t), uLobe, {0.3f, 0.7f}, bs)) {
          EXPECT_EQ(bs.delta, b.isDelta()) << t;
        }
      }
    }
  }
}

TEST(BsdfDelta, SmoothConductorIsAMirrorWithSchlickFresnel) {
  for (float f0 : {1.0f, 0.5f, 0.04f}) {
    Bsdf b = conductorBsdf(Vec3f(f0), 0);
    ASSERT_TRUE(b.isDelta());
    for (float t : {0.0f, 30.0f, 60.0f, 89.0f}) {
      Vec3f wo = direction(t);
      BsdfSample bs;
      ASSERT_TRUE(b.sample(wo, 0.3f, {0.2f, 0.9f}, bs));
      EXPECT_TRUE(bs.delta);
      EXPECT_NEAR(bs.wi.x, -wo.x, 1e-6f);
      EXPECT_NEAR(bs.wi.y, -wo.y, 1e-6f);
      EXPECT_NEAR(bs.wi.z, wo.z, 1e-6f);
      float expected = f0 + (1 - f0) * std::pow(1 - wo.z, 5.0f);
      EXPECT_NEAR(bs.weight.x, expected, 1e-5f) << f0 << " " << t;
      EXPECT_LE(bs.weight.x, 1.0f);
      EXPECT_EQ(b.pdf(wo, bs.wi), 0.0f);
      EXPECT_EQ(maxComponent(b.eval(wo, bs.wi)), 0.0f);
    }
    BsdfSample bs;
    EXPECT_FALSE(b.sample(direction(120), 0.5f, {0.5f, 0.5f}, bs))
        << "an opaque lobe seen from below";
  }
}

// The smooth dielectric reflects with probability F and refracts by Snell's
// law otherwise, with weight 1 (tint for transmission): a binomial test of the
// reflected fraction against fresnelDielectric.
TEST(BsdfDelta, SmoothDielectricFollowsFresnelAndSnell) {
  const float angles[] = {0, 30, 60, 85, 100, 140, 175};
  const int cases = 2 * int(std::size(angles));
  const double z = testing::twoSidedNormalQuantile(testing::sidak(kAlpha, cases));
  for (float ior : {1.5f, 1 / 1.5f}) {
    Bsdf b = dielectricBsdf(ior, 0, Vec3f(0.9f, 0.8f, 0.7f));
    ASSERT_TRUE(b.isDelta());
    for (float t : angles) {
      Vec3f wo = direction(t);
      float eta = wo.z > 0 ? ior : 1 / ior;  // n on the far side / n on wo's side
      float cosI = std::abs(wo.z);
      double F = fresnelDielectric(cosI, eta);
      TestRng rng(uint64_t(t * 1000 + ior * 10));
      constexpr int n = 200000;
      int reflected = 0;
      for (int k = 0; k < n; ++k) {
        BsdfSample bs;
        ASSERT_TRUE(b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, bs));
        ASSERT_TRUE(bs.delta);
        if (bs.wi.z * wo.z > 0) {
          ++reflected;
          ASSERT_NEAR(bs.wi.x, -wo.x, 1e-6f);
          ASSERT_NEAR(bs.wi.y, -wo.y, 1e-6f);
          ASSERT_NEAR(bs.wi.z, wo.z, 1e-6f);
          ASSERT_EQ(bs.weight, Vec3f(1));
        } else {
          // Snell: n_o sin(theta_o) = n_i sin(theta_i), in the plane of incidence.
          float sinO = std::sqrt(std::max(0.0f, 1 - wo.z * wo.z));
          float sinI = std::sqrt(std::max(0.0f, 1 - bs.wi.z * bs.wi.z));
          ASSERT_NEAR(sinO, eta * sinI, 1e-5f) << t << " " << ior;
          ASSERT_NEAR(bs.wi.x * wo.y - bs.wi.y * wo.x, 0.0f, 1e-5f)
              << "out of the plane of incidence";
          ASSERT_LE(bs.wi.x * wo.x + bs.wi.y * wo.y, 1e-6f)
              << "must cross to the other side of the normal";
          ASSERT_EQ(bs.weight, Vec3f(0.9f, 0.8f, 0.7f));
        }
      }
      double sd = std::sqrt(n * F * (1 - F));
      std::printf("[ fresnel  ] ior %.3f wo %5.1f deg: reflected %.5f expected F %.5f\n", ior, t,
                  double(reflected) / n, F);
      EXPECT_NEAR(reflected, n * F, z * sd + 1.0) << "ior " << ior << " theta " << t;
    }
  }
}

// ------------------------------------------------------------ reciprocity etc.

// f(wo, wi) = f(wi, wo) for reflection; for transmission, with this BSDF's
// convention (no 1/eta^2 radiance scaling), f(wo, wi) / n_i^2 is symmetric
// (n_i: index on wi's side).
TEST(BsdfReciprocity, EvalIsSymmetricUpToTheRefractiveIndexFactor) {
  std::vector<std::pair<std::string, Bsdf>> lobes = {
      {"diffuse", diffuseBsdf(Vec3f(0.7f))},
      {"conductor 0.3", conductorBsdf(Vec3f(0.9f), 0.3f)},
      {"conductor 0.8", conductorBsdf(Vec3f(0.5f), 0.8f)},
      {"dielectric 1.5 0.3", dielectricBsdf(1.5f, 0.3f)},
      {"dielectric 1.33 0.6", dielectricBsdf(1.33f, 0.6f)},
      {"dielectric 0.67 0.5", dielectricBsdf(1 / 1.5f, 0.5f)},
      {"oren-nayar 25", diffuseBsdf(Vec3f(0.7f), 25)},
      {"plastic 0.3", coatedBsdf(Vec3f(0.5f), Vec3f(0.4f), 0.3f, 1 / 1.5f, false)},
      {"layered 0.2", coatedBsdf(Vec3f(0.8f), Vec3f(1), 0.2f, 1.5f, true, 10)},
      {"fresnel blend 0.3", fresnelBlendBsdf(Vec3f(0.6f), Vec3f(0.2f), 0.3f)}};
  TestRng rng(7);
  for (const auto& [name, bsdf] : lobes) {
    const float ior = bsdf.transmits() ? (name.find("1.33") != std::string::npos   ? 1.33f
                                          : name.find("0.67") != std::string::npos ? 1 / 1.5f
                                                                                   : 1.5f)
                                       : 1.0f;
    int compared = 0, loose = 0;
    for (int k = 0; k < 20000; ++k) {
      auto randomDirection = [&] {
        float z = 1 - 2 * rng.uniform(), phi = 2 * kPi * rng.uniform();
        float r = std::sqrt(std::max(0.0f, 1 - z * z));
        return Vec3f{r * std::cos(phi), r * std::sin(phi), z};
      };
      Vec3f a = randomDirection(), b = randomDirection();
      if (std::abs(a.z) < 0.05f || std::abs(b.z) < 0.05f) continue;
      auto n = [&](Vec3f w) { return w.z > 0 ? 1.0f : ior; };
      float fab = bsdf.eval(a, b).x / std::abs(b.z) / (n(b) * n(b));
      float fba = bsdf.eval(b, a).x / std::abs(a.z) / (n(a) * n(a));
      if (fab == 0 && fba == 0) continue;
      ++compared;
      // Near the critical angle 1 - F loses digits in float (cos theta_t from
      // 1 - sin^2), so a few pairs may differ by up to ~1%; a missing factor
      // (eta^2, a cosine) would be far larger and everywhere. Values in the
      // far tails (below 1e-5, against peaks of 1 to 100) are float noise.
      float difference = std::abs(fab - fba), largest = std::max(fab, fba);
      if (difference > 1e-3f * largest + 1e-5f) ++loose;
      ASSERT_LE(difference, 2e-2f * largest + 1e-5f)
          << name << " a=(" << a.x << "," << a.y << "," << a.z << ") b=(" << b.x << "," << b.y
          << "," << b.z << "): " << fab << " vs " << fba;
    }
    EXPECT_LE(loose, compared / 200) << name;
    EXPECT_GT(compared, 1000) << name;
  }
}

TEST(BsdfFresnel, MatchesClosedForms) {
  // Normal incidence: ((n - 1) / (n + 1))^2, from either side.
  for (float n : {1.33f, 1.5f, 2.4f}) {
    float r0 = (n - 1) / (n + 1);
    EXPECT_NEAR(fresnelDielectric(1, n), r0 * r0, 1e-6f);
    EXPECT_NEAR(fresnelDielectric(1, 1 / n), r0 * r0, 1e-6f);
    // Brewster's angle: p-polarised reflectance vanishes, F = Rs / 2 with
    // rs = (1 - n^2) / (1 + n^2).
    float cosB = std::cos(std::atan(n));
    float rs = (1 - n * n) / (1 + n * n);
    EXPECT_NEAR(fresnelDielectric(cosB, n), 0.5f * rs * rs, 1e-5f);
    // Total internal reflection beyond the critical angle, and continuity at it.
    float cosCritical = std::sqrt(1 - 1 / (n * n));
    EXPECT_EQ(fresnelDielectric(cosCritical * 0.99f, 1 / n), 1.0f);
    EXPECT_EQ(fresnelDielectric(0.01f, 1 / n), 1.0f);
    EXPECT_LT(fresnelDielectric(cosCritical * 1.01f, 1 / n), 1.0f);
    EXPECT_GT(fresnelDielectric(cosCritical * 1.01f, 1 / n),
              fresnelDielectric(cosCritical * 1.1f, 1 / n));
    // Grazing incidence reflects everything.
    EXPECT_NEAR(fresnelDielectric(0, n), 1.0f, 1e-6f);
    // The same interface seen from both sides: F(theta_i, n) = F(theta_t, 1/n).
    for (float cosI = 0.05f; cosI <= 1; cosI += 0.05f) {
      float sinT = std::sqrt(1 - cosI * cosI) / n;
      float cosT = std::sqrt(1 - sinT * sinT);
      EXPECT_NEAR(fresnelDielectric(cosI, n), fresnelDielectric(cosT, 1 / n), 1e-5f)
          << n << " " << cosI;
      float f = fresnelDielectric(cosI, n);
      EXPECT_GE(f, 0.0f);
      EXPECT_LE(f, 1.0f);
    }
  }
  // A value from the textbook: glass at 45 degrees, Rs = 0.0920, Rp = 0.0085.
  EXPECT_NEAR(fresnelDielectric(std::cos(kPi / 4), 1.5f), 0.5f * (0.092013f + 0.0084663f), 2e-5f);
}

TEST(BsdfDiffuse, IsCosineWeightedWithAlbedoWeight) {
  Bsdf b = diffuseBsdf(Vec3f(0.2f, 0.5f, 0.8f));
  Vec3f wo = direction(40);
  BsdfSample bs;
  ASSERT_TRUE(b.sample(wo, 0.5f, {0.3f, 0.6f}, bs));
  EXPECT_NEAR(bs.pdf, bs.wi.z / kPi, 1e-6f);
  EXPECT_NEAR(bs.weight.y, 0.5f, 1e-6f);
  EXPECT_NEAR(b.eval(wo, bs.wi).z, 0.8f * bs.wi.z / kPi, 1e-6f);
  EXPECT_FALSE(b.sample(direction(100), 0.5f, {0.3f, 0.6f}, bs)) << "opaque lobes see only +z";
  EXPECT_EQ(b.pdf(wo, direction(100)), 0.0f);
}

}  // namespace
}  // namespace ferry
