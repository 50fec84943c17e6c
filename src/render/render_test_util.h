// Shared by the render tests only (included from *_test.cpp): the statistics
// the stochastic tests use to set their thresholds, and small scenes built in
// code so the tests do not depend on loaders or built-ins.
//
// Thresholds come from a significance level and the number of tests made at
// it (Sidak correction), never from a hand-picked tolerance, so a test fails
// about as often as it says it will and a real bias of a few standard errors
// is caught.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <tbb/global_control.h>

#include "core/math.h"
#include "path/path.h"
#include "render/frame_buffer.h"
#include "render/lights.h"
#include "render/ray_traversal.h"
#include "render/wavefront_renderer.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"

namespace ferry::testing {

// ---------------------------------------------------------------- statistics

// Per-test significance so that `tests` independent tests at it have a
// family-wise false-alarm rate of `alpha` (Sidak).
inline double sidak(double alpha, double tests) {
  return 1 - std::pow(1 - alpha, 1 / tests);
}

// Regularized upper incomplete gamma Q(a, x) (Numerical Recipes 6.2).
inline double regularizedGammaQ(double a, double x) {
  if (x <= 0) return 1;
  const double lnGammaA = std::lgamma(a);
  if (x < a + 1) {  // series for P
    double sum = 1 / a, term = sum;
    for (int n = 1; n < 100000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-15) break;
    }
    return 1 - sum * std::exp(-x + a * std::log(x) - lnGammaA);
  }
  // Continued fraction for Q (modified Lentz).
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-15) break;
  }
  return std::exp(-x + a * std::log(x) - lnGammaA) * h;
}

// P(X >= chi2) for a chi-square variable with `dof` degrees of freedom.
inline double chiSquareSurvival(double chi2, double dof) {
  return regularizedGammaQ(dof / 2, chi2 / 2);
}

// Regularized incomplete beta I_x(a, b) (Numerical Recipes 6.4).
inline double regularizedIncompleteBeta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  auto continuedFraction = [](double a, double b, double x) {
    const double tiny = 1e-300;
    double qab = a + b, qap = a + 1, qam = a - 1, c = 1, d = 1 - qab * x / qap;
    if (std::abs(d) < tiny) d = tiny;
    d = 1 / d;
    double h = d;
    for (int m = 1; m < 100000; ++m) {
      int m2 = 2 * m;
      double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
      d = 1 + aa * d;
      if (std::abs(d) < tiny) d = tiny;
      c = 1 + aa / c;
      if (std::abs(c) < tiny) c = tiny;
      d = 1 / d;
      h *= d * c;
      aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
      d = 1 + aa * d;
      if (std::abs(d) < tiny) d = tiny;
      c = 1 + aa / c;
      if (std::abs(c) < tiny) c = tiny;
      d = 1 / d;
      double delta = d * c;
      h *= delta;
      if (std::abs(delta - 1) < 1e-15) break;
    }
    return h;
  };
  double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) +
                          b * std::log1p(-x));
  if (x < (a + 1) / (a + b + 2)) return front * continuedFraction(a, b, x) / a;
  return 1 - front * continuedFraction(b, a, 1 - x) / b;
}

// P(|T| >= |t|) for Student's t with `dof` degrees of freedom.
inline double studentTwoSidedP(double t, double dof) {
  if (!std::isfinite(t)) return 0;
  return regularizedIncompleteBeta(dof / 2, 0.5, dof / (dof + t * t));
}

// Welch's t-test of two means from their estimated variances-of-the-mean
// (va, vb) and the degrees of freedom of those estimates; returns the
// two-sided p-value (1 when both variances are zero and the means agree).
inline double welchP(double meanA, double varMeanA, double dofA, double meanB, double varMeanB,
                     double dofB) {
  double v = varMeanA + varMeanB;
  if (v <= 0) return meanA == meanB ? 1.0 : 0.0;
  double t = (meanA - meanB) / std::sqrt(v);
  double dof = v * v / (varMeanA * varMeanA / dofA + varMeanB * varMeanB / dofB);
  return studentTwoSidedP(t, dof);
}

// z such that P(|Z| > z) = p for a standard normal Z (two-sided), by bisection on erfc.
inline double twoSidedNormalQuantile(double p) {
  double lo = 0, hi = 40;
  for (int i = 0; i < 200; ++i) {
    double mid = 0.5 * (lo + hi);
    if (std::erfc(mid / std::sqrt(2.0)) > p)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}
// z such that P(Z > z) = p (one-sided).
inline double oneSidedNormalQuantile(double p) {
  return twoSidedNormalQuantile(2 * p);
}

// Running mean and variance (Welford), in double.
struct MeanVariance {
  double n = 0, mean = 0, m2 = 0;
  void add(double x) {
    n += 1;
    double d = x - mean;
    mean += d / n;
    m2 += d * (x - mean);
  }
  double variance() const { return n > 1 ? m2 / (n - 1) : 0; }  // sample variance
  double standardError() const { return n > 0 ? std::sqrt(variance() / n) : 0; }
};

// A deterministic uniform generator for the BSDF tests (splitmix64).
struct TestRng {
  uint64_t state;
  explicit TestRng(uint64_t seed) : state(seed) {}
  uint64_t next64() {
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  float uniform() { return float(next64() >> 40) * 0x1p-24f; }
};

// Contributions pass through half precision once (the shadow ray's or the
// path's stored throughput), so even a noiseless estimate may sit this far
// (relative) from the exact value: round-to-nearest is within 2^-11.
constexpr double kHalfRelativeError = 1.0 / 2048.0;

// ------------------------------------------------------------------- scenes

// A UV sphere, flat-shaded (no vertex normals) unless `smoothNormals`; the
// winding makes geometric normals point outwards.
inline Mesh makeSphere(Vec3f center, float radius, int rings, int segments, int32_t material,
                       bool smoothNormals = false) {
  Mesh m;
  m.name = "sphere";
  m.material = material;
  for (int r = 0; r <= rings; ++r) {
    float theta = kPi * float(r) / float(rings);
    for (int s = 0; s <= segments; ++s) {
      float phi = 2 * kPi * float(s) / float(segments);
      Vec3f n{std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
      m.positions.push_back(center + n * radius);
      if (smoothNormals) m.normals.push_back(n);
      m.uvs.push_back({float(s) / float(segments), 1 - float(r) / float(rings)});
    }
  }
  auto index = [&](int r, int s) { return int32_t(r * (segments + 1) + s); };
  for (int r = 0; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      int32_t a = index(r, s), b = index(r, s + 1), c = index(r + 1, s), d = index(r + 1, s + 1);
      if (r != 0) m.indices.push_back({a, b, c});
      if (r != rings - 1) m.indices.push_back({b, d, c});
    }
  }
  return m;
}

// A parallelogram corner + s*edgeU + t*edgeV, (s, t) in [0, 1]^2, uv = (s, t);
// its geometric normal is cross(edgeU, edgeV).
inline Mesh makeQuad(Vec3f corner, Vec3f edgeU, Vec3f edgeV, int32_t material) {
  Mesh m;
  m.name = "quad";
  m.material = material;
  m.positions = {corner, corner + edgeU, corner + edgeU + edgeV, corner + edgeV};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

inline Material diffuseMaterial(Vec3f albedo) {
  Material m;
  m.name = "diffuse";
  m.baseColor = albedo;
  return m;
}

// ---------------------------------------------------------------- rendering

// Everything a one-rank render needs, built over `scene` (which must outlive it).
struct RenderSetup {
  std::unique_ptr<TraceBackend> geometry;
  std::unique_ptr<LightSampler> lights;
  std::unique_ptr<LocalTraversal<Path8>> traversal;
  std::unique_ptr<WavefrontRenderer<Path8>> renderer;
  RenderSettings settings;

  RenderSetup(const Scene& scene, const RenderSettings& s) : settings(s) {
    geometry = makeEmbreeBackend(scene);
    lights = std::make_unique<LightSampler>(scene, s.lightChoice);
    traversal = std::make_unique<LocalTraversal<Path8>>(*geometry);
    renderer =
        std::make_unique<WavefrontRenderer<Path8>>(scene, *geometry, *lights, *traversal, settings);
  }
  // Renders frame `frame` into a fresh buffer and returns its per-pixel mean
  // (the buffer's sums divided by the samples per pixel).
  std::vector<Vec3f> frameMean(int frame, FrameStats* statsOut = nullptr) {
    FrameBuffer fb(settings.imageWidth(), settings.imageHeight());
    FrameStats stats = renderer->renderFrame(frame, fb);
    if (statsOut) *statsOut = stats;
    std::vector<Vec3f> out = fb.sum();
    for (Vec3f& v : out) v = v * (1.0f / float(settings.samplesPerPixel));
    return out;
  }
};

// Per-pixel, per-channel mean and variance over independent frames (each a
// batch of `samplesPerPixel` samples with its own sample indices).
struct PixelStatistics {
  int width = 0, height = 0;
  std::vector<MeanVariance> channel[3];  // of the frame means
  uint64_t retraceMisses = 0;

  void init(int w, int h) {
    width = w;
    height = h;
    for (auto& c : channel) c.assign(size_t(w) * h, {});
  }
  void addFrame(const std::vector<Vec3f>& frameMean) {
    for (size_t i = 0; i < frameMean.size(); ++i)
      for (int k = 0; k < 3; ++k) channel[k][i].add(frameMean[i][k]);
  }
  // Mean over all pixels of channel k, and its standard error from the
  // per-pixel variance across frames (pixels are independent of each other).
  void imageMean(int k, double& mean, double& standardError) const {
    double sum = 0, var = 0;
    for (const MeanVariance& mv : channel[k]) {
      sum += mv.mean;
      var += mv.variance() / mv.n;
    }
    double n = double(channel[k].size());
    mean = sum / n;
    standardError = std::sqrt(var) / n;
  }
};

inline PixelStatistics renderStatistics(Scene& scene, const RenderSettings& settings, int frames) {
  RenderSetup setup(scene, settings);
  PixelStatistics stats;
  stats.init(settings.imageWidth(), settings.imageHeight());
  for (int f = 0; f < frames; ++f) {
    FrameStats fs;
    stats.addFrame(setup.frameMean(f, &fs));
    stats.retraceMisses += fs.retraceMisses;
  }
  return stats;
}

// `scene` under a white sky (constant environment 1), seen by `view`, direct
// light only (max depth 1), 16 x 16 pixels, 16 spp, 8 frames: a Lambertian
// surface's expected pixel value is then its albedo.
inline PixelStatistics renderUnderWhiteSky(Scene scene, const CameraView& view) {
  scene.environment.color = Vec3f(1);
  scene.views.push_back(view);
  RenderSettings settings;
  settings.width = settings.height = 16;
  settings.samplesPerPixel = 16;
  settings.maxDepth = 1;
  return renderStatistics(scene, settings, 8);
}

}  // namespace ferry::testing
