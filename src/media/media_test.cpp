// Media against closed forms: the grid lookup, majorants, the phase
// function, and both trackers' means against the transmittance they estimate.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "core/random.h"
#include "media/density_grid.h"
#include "media/majorant_grid.h"
#include "media/medium.h"
#include "media/phase.h"
#include "media/tracking.h"
#include "media/transfer_function.h"

namespace ferry {
namespace {

TEST(DensityGrid, LooksUpLikePbrt) {
  DensityGrid g(2, 1, 1, {1, 3});
  // Sample centres at x = 0.25 and 0.75; halfway between them the mean.
  EXPECT_FLOAT_EQ(g.lookup({0.25f, 0.5f, 0.5f}), 1);
  EXPECT_FLOAT_EQ(g.lookup({0.75f, 0.5f, 0.5f}), 3);
  EXPECT_FLOAT_EQ(g.lookup({0.5f, 0.5f, 0.5f}), 2);
  // Towards a face the density fades to half at the face (samples outside are 0).
  EXPECT_FLOAT_EQ(g.lookup({0.0f, 0.5f, 0.5f}), 0.5f);
  EXPECT_FLOAT_EQ(g.lookup({2.0f, 0.5f, 0.5f}), 0);
  EXPECT_FLOAT_EQ(g.lookup({0.5f, -5.0f, 0.5f}), 0);
  EXPECT_EQ(g.minValue(), 1);
  EXPECT_EQ(g.maxValue(), 3);
}

TEST(DensityGrid, RefusesBadInput) {
  EXPECT_THROW(DensityGrid(2, 2, 2, {1, 2, 3}), std::invalid_argument);
  EXPECT_THROW(DensityGrid(0, 1, 1, {}), std::invalid_argument);
  EXPECT_THROW(DensityGrid(2, 1, 1, {1, -1}), std::invalid_argument);
  EXPECT_THROW(DensityGrid(2, 1, 1, {1, std::nanf("")}), std::invalid_argument);
}

TEST(MajorantGrid, BoundsEveryLookupInItsCellFromAboveAndBelow) {
  std::vector<float> v(20 * 17 * 9);
  uint32_t h = 1;
  for (float& x : v) x = random01FromBits(h = hashMix(h + 1)) * 5;
  DensityGrid g(20, 17, 9, v);
  MajorantGrid m(g, 4);
  auto next = [&] { return random01FromBits(h = hashMix(h + 1)); };
  for (int i = 0; i < 20000; ++i) {
    const float x = next(), y = next(), z = next();
    const Vec3f p{x, y, z};
    int cx = std::min(int(p.x * 4), 3), cy = std::min(int(p.y * 4), 3),
        cz = std::min(int(p.z * 4), 3);
    ASSERT_LE(g.lookup(p), m.at(cx, cy, cz) * (1 + 1e-6f)) << p.x << " " << p.y << " " << p.z;
    ASSERT_GE(g.lookup(p), m.controlAt(cx, cy, cz).x * (1 - 1e-6f))
        << p.x << " " << p.y << " " << p.z;
  }
}

TEST(MajorantGrid, WalksTheCellsAlongARayInOrder) {
  DensityGrid g(4, 4, 4, std::vector<float>(64, 1));
  MajorantGrid m(g, 4);
  // Along a diagonal through the cube: each visited piece follows the last.
  Vec3f o{-0.1f, 0.05f, 0.5f}, d = normalize(Vec3f(1, 0.7f, 0.1f));
  float t0 = 0, t1 = 100;
  ASSERT_TRUE(clipToUnitCube(o, d, t0, t1));
  float last = t0, covered = 0;
  int cells = 0;
  m.walk(o, d, t0, t1, [&](float a, float b, float, const Vec3f&) {
    EXPECT_NEAR(a, last, 1e-5f);
    EXPECT_GT(b, a);
    covered += b - a;
    last = b;
    ++cells;
    return true;
  });
  EXPECT_NEAR(covered, t1 - t0, 1e-4f);
  EXPECT_GE(cells, 4);
  EXPECT_LE(cells, 10);
}

TEST(Phase, HenyeyGreensteinIsNormalisedAndSamplesItsMeanCosine) {
  for (float g : {-0.6f, 0.0f, 0.3f, 0.9f}) {
    const Vec3f wo = normalize(Vec3f(0.3f, -0.2f, 0.9f));
    double integral = 0, meanCos = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
      const float u1 = (float(i) + 0.5f) / float(n), u2 = random01FromBits(hashMix(uint32_t(i)));
      // Uniform sphere directions for the integral.
      const float z = 1 - 2 * u1, r = std::sqrt(std::max(0.0f, 1 - z * z));
      const Vec3f w{r * std::cos(2 * kPi * u2), r * std::sin(2 * kPi * u2), z};
      integral += phaseValue(wo, w, g) * 4 * kPi;
      Vec3f wi;
      const float pdf = samplePhase(wo, g, {u1, u2}, wi);
      EXPECT_NEAR(pdf, phaseValue(wo, wi, g), 1e-3f * pdf + 1e-6f);
      meanCos += dot(-wo, wi);
    }
    EXPECT_NEAR(integral / n, 1, 0.02) << g;
    EXPECT_NEAR(meanCos / n, g, 0.01) << g;
  }
}

// A grid of constant density c over the unit cube (identity placement),
// crossed along x through its middle: the optical depth is
// sigma_t c (1 - 0.25 / nx) (half a voxel's fade at each face).
Medium constantSlab(Vec3f sigmaA, Vec3f sigmaS, float c, int n) {
  auto grid = std::make_shared<DensityGrid>(n, n, n, std::vector<float>(size_t(n * n * n), c));
  return gridMedium("slab", sigmaA, sigmaS, 0, grid, Affine3f::identity(),
                    Box3f{{0, 0, 0}, {1, 1, 1}});
}

TEST(Tracking, BothTransmittanceEstimatorsAverageToTheClosedForm) {
  const Medium m = constantSlab({0.4f, 1.0f, 2.0f}, {0.6f, 0.5f, 0.0f}, 1.5f, 8);
  const Vec3f o{-1, 0.5f, 0.5f}, d{1, 0, 0};
  const float depth = 1.5f * (1 - 0.25f / 8);
  for (auto estimator : {TransmittanceEstimator::Ratio, TransmittanceEstimator::Delta}) {
    MediumCounts counts;
    Vec3f sum{0, 0, 0};
    const int n = 40000;
    for (int i = 0; i < n; ++i) {
      TrackingRandom random(hashMix(uint32_t(i) * 7 + 3), 0);
      sum += transmittance(m, o, d, 0, 3, estimator, random, counts);
    }
    const Vec3f mean = sum * (1.0f / n);
    const Vec3f sigmaT = m.sigmaT();
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(mean[c], std::exp(-sigmaT[c] * depth), 0.01) << int(estimator) << " " << c;
    EXPECT_GT(counts.nullCollisions, 0u);
  }
}

TEST(Tracking, FreeFlightPassesWithTheTransmittanceAndScattersWithTheAlbedo) {
  // Chromatic: the expected weight of passing is T per channel, and of
  // scattering (1 - T) times the albedo, under spectral tracking.
  const Vec3f sigmaA{0.2f, 0.8f, 1.5f}, sigmaS{1.0f, 0.6f, 0.3f};
  for (bool homogeneous : {false, true}) {
    Medium m = constantSlab(sigmaA, sigmaS, 1.0f, 8);
    float length = 1 - 0.25f / 8;
    if (homogeneous) {
      m = Medium{};
      m.sigmaA = sigmaA;
      m.sigmaS = sigmaS;
      length = 1;
    }
    const Vec3f o{0, 0.5f, 0.5f}, d{1, 0, 0};
    Vec3f passed{0, 0, 0}, scattered{0, 0, 0};
    MediumCounts counts;
    const int n = 60000;
    for (int i = 0; i < n; ++i) {
      TrackingRandom random(hashMix(uint32_t(i) * 13 + 1), 0);
      const FreeFlight f = sampleFreeFlight(m, o, d, 0, 1, random, counts);
      if (f.event == FreeFlight::Event::Passed) passed += f.weight;
      if (f.event == FreeFlight::Event::Scattered) scattered += f.weight;
    }
    const Vec3f sigmaT = sigmaA + sigmaS;
    for (int c = 0; c < 3; ++c) {
      const float t = std::exp(-sigmaT[c] * length);
      EXPECT_NEAR(passed[c] / n, t, 0.015) << homogeneous << " " << c;
      EXPECT_NEAR(scattered[c] / n, (1 - t) * sigmaS[c] / sigmaT[c], 0.015)
          << homogeneous << " " << c;
    }
  }
}

TEST(Tracking, HomogeneousEmissionIsTheClosedFormIntegral) {
  Medium m;
  m.sigmaA = {1, 2, 0};
  m.sigmaS = {1, 0, 0};
  m.emission = {3, 3, 3};
  MediumCounts counts;
  TrackingRandom random(7, 0);
  const FreeFlight f = sampleFreeFlight(m, {0, 0, 0}, {0, 0, 1}, 0, 0.5f, random, counts);
  EXPECT_NEAR(f.emitted.x, 1 * 3 * (1 - std::exp(-2 * 0.5f)) / 2, 1e-5f);
  EXPECT_NEAR(f.emitted.y, 2 * 3 * (1 - std::exp(-2 * 0.5f)) / 2, 1e-5f);
  EXPECT_EQ(f.emitted.z, 0);
}

TEST(TransferFunction, InterpolatesItsPointsAndBoundsItsOpacity) {
  const TransferFunction tf({{0.2f, {1, 0, 0}}, {0.6f, {0, 0, 1}}},
                            {{0.0f, 0.0f}, {0.5f, 2.0f}, {1.0f, 1.0f}}, 3);
  EXPECT_EQ(tf.color(0.0f), Vec3f(1, 0, 0));  // flat before the first point
  EXPECT_EQ(tf.color(1.0f), Vec3f(0, 0, 1));  // and after the last
  EXPECT_NEAR(tf.color(0.4f).x, 0.5f, 1e-6f);
  EXPECT_NEAR(tf.opacity(0.25f), 1.0f, 1e-6f);
  EXPECT_NEAR(tf.opacity(0.75f), 1.5f, 1e-6f);
  // The peak between two values counts.
  const auto [lo, hi] = tf.opacityRange(0.25f, 0.75f);
  EXPECT_NEAR(lo, 1.0f, 1e-6f);
  EXPECT_NEAR(hi, 2.0f, 1e-6f);
  EXPECT_THROW(TransferFunction({}, {{0, 1}}, 1), std::invalid_argument);
  EXPECT_THROW(TransferFunction({{0.5f, {1, 1, 1}}, {0.4f, {1, 1, 1}}}, {{0, 1}}, 1),
               std::invalid_argument);
  EXPECT_THROW(TransferFunction({{0.5f, {2, 1, 1}}}, {{0, 1}}, 1), std::invalid_argument);
  EXPECT_THROW(TransferFunction({{0.5f, {1, 1, 1}}}, {{0, -1}}, 1), std::invalid_argument);
  EXPECT_THROW(TransferFunction({{0.5f, {1, 1, 1}}}, {{0, 1}}, -2), std::invalid_argument);
}

TEST(Tracking, ATransferFunctionVolumeTransmitsByItsOpacity) {
  // Values 0.5 everywhere through a ramp to opacity 1 at 1, scale 2: sigma_t
  // 1 inside (fading at the faces as the values do).
  auto tf = std::make_shared<TransferFunction>(
      std::vector<TransferFunction::ColorPoint>{{0, {0.5f, 0.5f, 0.5f}}},
      std::vector<TransferFunction::OpacityPoint>{{0, 0}, {1, 1}}, 2.0f);
  const int n = 8;
  const Medium m = transferFunctionMedium(
      "tf", std::make_shared<DensityGrid>(n, n, n, std::vector<float>(n * n * n, 0.5f)), tf,
      Box3f{{0, 0, 0}, {1, 1, 1}});
  const float depth = 1 - 0.25f / n;
  Vec3f sum{0, 0, 0};
  MediumCounts counts;
  const int samples = 20000;
  for (int i = 0; i < samples; ++i) {
    TrackingRandom random(hashMix(uint32_t(i) + 99), 0);
    sum += transmittance(m, {-1, 0.5f, 0.5f}, {1, 0, 0}, 0, 3, TransmittanceEstimator::Ratio,
                         random, counts);
  }
  EXPECT_NEAR(sum.x / samples, std::exp(-depth), 0.01);
}

// The integral of f along o + t d over [0, 1], by the midpoint rule.
template <typename F>
Vec3f quadrature(F&& f, int steps = 4000) {
  Vec3f sum{0, 0, 0};
  for (int i = 0; i < steps; ++i) sum += f((float(i) + 0.5f) / float(steps));
  return sum * (1.0f / float(steps));
}

// An rgb grid whose voxels vary: sigma_a and sigma_s per channel.
Medium testRgbGrid(bool emitting) {
  const int n = 4;
  auto grids = std::make_shared<RgbGrids>();
  uint32_t h = 5;
  for (RgbGrids::Channels* g : {&grids->sigmaA, &grids->sigmaS, &grids->emission}) {
    if (g == &grids->emission && !emitting) continue;
    for (auto& channel : *g) {
      std::vector<float> v(n * n * n);
      for (float& x : v) x = random01FromBits(h = hashMix(h + 1)) * 1.5f;
      channel = std::make_shared<DensityGrid>(n, n, n, v);
    }
  }
  return rgbGridMedium("rgb", grids, 2.0f, 3.0f, 0, Affine3f::identity(),
                       Box3f{{0, 0, 0}, {1, 1, 1}});
}

TEST(Tracking, RatioTrackingThroughAnRgbGridMatchesQuadraturePerChannel) {
  const Medium m = testRgbGrid(false);
  const Vec3f o{0, 0.3f, 0.6f}, d = normalize(Vec3f{1, 0.2f, -0.1f});
  // The true optical depth along the ray inside the unit cube (to x = 1).
  const float length = 1 / d.x;
  const Vec3f depth = quadrature([&](float u) {
                        Vec3f sa, ss;
                        m.coefficients(o + d * (u * length), sa, ss);
                        return sa + ss;
                      }) *
                      length;
  Vec3f sum{0, 0, 0};
  MediumCounts counts;
  const int samples = 40000;
  for (int i = 0; i < samples; ++i) {
    TrackingRandom random(hashMix(uint32_t(i) * 3 + 11), 0);
    sum += transmittance(m, o, d, 0, length, TransmittanceEstimator::Ratio, random, counts);
  }
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / samples, std::exp(-depth[c]), 0.01) << c;
}

TEST(Tracking, AGridMediumEmitsTheIntegralOfTransmittanceAbsorptionAndItsLe) {
  // The light an emitting grid gives a ray is the integral of T sigma_a Le;
  // free flights add it where they are absorbed.
  const Medium m = testRgbGrid(true);
  const Vec3f o{0, 0.45f, 0.55f}, d{1, 0, 0};
  Vec3f tau{0, 0, 0};
  const int steps = 4000;
  Vec3f expected{0, 0, 0};
  for (int i = 0; i < steps; ++i) {
    const Vec3f p = o + d * ((float(i) + 0.5f) / steps);
    Vec3f sa, ss;
    m.coefficients(p, sa, ss);
    const Vec3f st = sa + ss;
    const Vec3f mid = tau + st * (0.5f / steps);
    const Vec3f t{std::exp(-mid.x), std::exp(-mid.y), std::exp(-mid.z)};
    expected += t * sa * m.emittedAt(p) * (1.0f / steps);
    tau += st * (1.0f / steps);
  }
  Vec3f sum{0, 0, 0};
  MediumCounts counts;
  const int samples = 100000;
  for (int i = 0; i < samples; ++i) {
    TrackingRandom random(hashMix(uint32_t(i) * 5 + 2), 0);
    sum += sampleFreeFlight(m, o, d, 0, 1, random, counts).emitted;
  }
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(sum[c] / samples, expected[c], 0.03 * expected[c] + 0.003) << c;
}

TEST(Cloud, IsDenseBelowHalfHeightAndEmptyAtTheTop) {
  CloudDensity c;
  c.box = Box3f{{0, 0, 0}, {1, 1, 1}};
  uint32_t h = 3;
  for (int i = 0; i < 2000; ++i) {
    const float x = random01FromBits(h = hashMix(h + 1)), z = random01FromBits(h = hashMix(h + 1));
    const float y = random01FromBits(h = hashMix(h + 1));
    const float d = c.at({x, y, z});
    ASSERT_GE(d, 0);
    ASSERT_LE(d, 1);
    // pbrt-v4's altitude term: 2 (0.5 - y) alone reaches 1 at y = 0.
    EXPECT_EQ(c.at({x, 0, z}), 1);
    EXPECT_EQ(c.at({x, 1, z}), 0);
  }
  // The noise makes it vary in between.
  float lo = 1, hi = 0;
  for (int i = 0; i < 200; ++i) {
    const float d = c.at({float(i) / 200, 0.7f, 0.3f});
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  EXPECT_GT(hi - lo, 0.2f);
  // Its medium's one majorant bounds it: transmittance from ratio tracking
  // averages to the quadrature of the density.
  const Medium m = cloudMedium("cloud", Vec3f(1), Vec3f(2), 0, c, Affine3f::identity());
  const Vec3f o{0.1f, 0.6f, 0}, d{0, 0, 1};
  const float depth = quadrature([&](float u) { return Vec3f(c.at(o + d * u)); }).x * 3;
  Vec3f sum{0, 0, 0};
  MediumCounts counts;
  const int samples = 20000;
  for (int i = 0; i < samples; ++i) {
    TrackingRandom random(hashMix(uint32_t(i) * 9 + 4), 0);
    sum += transmittance(m, o, d, 0, 1, TransmittanceEstimator::Ratio, random, counts);
  }
  EXPECT_NEAR(sum.x / samples, std::exp(-depth), 0.01);
}

TEST(TemperatureEmission, IsABlackbodyTableAboveAHundredKelvin) {
  TemperatureEmission t;
  t.kelvin = std::make_shared<DensityGrid>(1, 1, 1, std::vector<float>{1000});
  t.table = {Vec3f(0), Vec3f(1, 0, 0), Vec3f(3, 2, 0)};
  t.step = 1000;
  t.offset = 500;
  t.scale = 3;  // (1000 - 500) x 3 = 1500 K at the centre: halfway between entries 1 and 2
  const Vec3f e = t.at({0.5f, 0.5f, 0.5f});
  EXPECT_FLOAT_EQ(e.x, 2);
  EXPECT_FLOAT_EQ(e.y, 1);
  t.offset = 990;  // 30 K: nothing
  EXPECT_EQ(t.at({0.5f, 0.5f, 0.5f}).x, 0);
  t.offset = 0;
  t.scale = 100;  // beyond the table: its last entry
  EXPECT_EQ(t.at({0.5f, 0.5f, 0.5f}).x, 3);
}

TEST(MajorantGrid, ATransferFunctionChangeRebuildsFromTheKeptRanges) {
  std::vector<float> v(10 * 10 * 10);
  uint32_t h = 1;
  for (float& x : v) x = random01FromBits(h = hashMix(h + 1));
  auto grid = std::make_shared<DensityGrid>(10, 10, 10, v);
  auto ramp = [](float scale) {
    return std::make_shared<TransferFunction>(
        std::vector<TransferFunction::ColorPoint>{{0, Vec3f(1)}},
        std::vector<TransferFunction::OpacityPoint>{{0, 0}, {1, 1}}, scale);
  };
  Medium m = transferFunctionMedium("tf", grid, ramp(2), Box3f{{0, 0, 0}, {1, 1, 1}});
  setTransferFunction(m, ramp(6));
  const Medium fresh = transferFunctionMedium("tf", grid, ramp(6), Box3f{{0, 0, 0}, {1, 1, 1}});
  for (int z = 0; z < m.majorants->cells(2); ++z)
    for (int y = 0; y < m.majorants->cells(1); ++y)
      for (int x = 0; x < m.majorants->cells(0); ++x) {
        EXPECT_EQ(m.majorants->at(x, y, z), fresh.majorants->at(x, y, z));
        EXPECT_EQ(m.majorants->controlAt(x, y, z), fresh.majorants->controlAt(x, y, z));
      }
}

}  // namespace
}  // namespace ferry
