// Which shadow-ray transmittance estimator reaches a given error first?
// (docs/volumes.md, "Shadow rays".) Samples rays the way next-event
// estimation makes them inside a scene's first grid medium: from points
// where there is medium, in uniformly random directions, to infinity through
// the medium boundaries. Each ray's true transmittance is the mean of many
// ratio-tracking estimates; each estimator's mean squared error per estimate
// and time per estimate give its error at equal time, and the ratio of the
// two is the figure:
//
//   equal-time error ratio = sqrt(MSE_delta t_delta / (MSE_ratio t_ratio))
//
//   build/bench/transmittance_estimators [SCENE] [--rays N] [--reference K]
//       [--estimates M] [--min-ratio R]   (exit 1 when the ratio is below R)
#include <fmt/format.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <vector>

#include "core/error.h"
#include "core/random.h"
#include "io/scene_loader.h"
#include "media/tracking.h"
#include "render/media_along_rays.h"
#include "scene/scene.h"

using namespace ferry;

namespace {

struct Ray {
  Vec3f o, d;
  int32_t medium;
  double truth = 0;
};

struct Measured {
  double mse = 0;          // per estimate, against the rays' truths
  double secondsEach = 0;  // per estimate
  MediumCounts counts;
};

Measured measure(const MediaAlongRays& media, const std::vector<Ray>& rays,
                 TransmittanceEstimator estimator, int estimates, uint32_t seed) {
  Measured m;
  double squared = 0;
  const auto start = std::chrono::steady_clock::now();
  for (size_t i = 0; i < rays.size(); ++i)
    for (int k = 0; k < estimates; ++k) {
      TrackingRandom random(hashCombine(seed, uint32_t(i * 7919 + size_t(k))), 0);
      const Vec3f t = media.transmittance(rays[i].o, rays[i].d, kInfinity, rays[i].medium,
                                          estimator, random, m.counts);
      const double e = double(t.x) - rays[i].truth;
      squared += e * e;
    }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double n = double(rays.size()) * double(estimates);
  m.mse = squared / n;
  m.secondsEach = seconds / n;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenePath = "../shared/scenes/smoke/smoke.pbrt";
  int rays = 2000, reference = 1024, estimates = 64;
  double minRatio = 0;
  CLI::App app{
      "Shadow-ray transmittance through a scene's grid medium: ratio tracking against "
      "delta tracking at equal time (docs/volumes.md)."};
  app.add_option("scene", scenePath, "A scene with a grid medium")->capture_default_str();
  app.add_option("--rays", rays, "Rays sampled")->capture_default_str();
  app.add_option("--reference", reference, "Ratio-tracking estimates per ray for its truth")
      ->capture_default_str();
  app.add_option("--estimates", estimates, "Estimates per ray per estimator")
      ->capture_default_str();
  app.add_option("--min-ratio", minRatio, "Exit 1 when the equal-time error ratio is below this")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    LoadOptions options;
    options.warn = [](const std::string&) {};
    const Scene scene = loadScene(scenePath, options);
    int32_t grid = kNoMedium;
    for (size_t m = 0; m < scene.media.size(); ++m)
      if (!scene.media[m].homogeneous()) {
        grid = int32_t(m);
        break;
      }
    if (grid == kNoMedium) throw InputError(scenePath + ": no grid medium");
    const Medium& medium = scene.media[size_t(grid)];
    const MediaAlongRays media(scene);
    const Affine3f worldFromGrid = medium.gridFromWorld.inverse();
    // Origins where the density is at least a tenth of its largest (where
    // shading happens), uniformly random directions.
    std::vector<Ray> sample;
    const float threshold = 0.1f * medium.density->maxValue();
    for (uint32_t i = 0; sample.size() < size_t(rays) && i < 100000000u; ++i) {
      auto u = [&](uint32_t dim) { return random01FromBits(hashCombine(hashMix(i), dim)); };
      const Vec3f p{u(0), u(1), u(2)};
      if (!(medium.density->lookup(p) >= threshold)) continue;
      const float z = 1 - 2 * u(3), r = std::sqrt(std::max(0.0f, 1 - z * z)), phi = 2 * kPi * u(4);
      sample.push_back(
          {worldFromGrid.transformPoint(p), {r * std::cos(phi), r * std::sin(phi), z}, grid});
    }
    for (size_t i = 0; i < sample.size(); ++i) {
      MediumCounts ignored;
      double sum = 0;
      for (int k = 0; k < reference; ++k) {
        TrackingRandom random(hashCombine(0xabcdefu, uint32_t(i * 104729 + size_t(k))), 0);
        sum += media
                   .transmittance(sample[i].o, sample[i].d, kInfinity, grid,
                                  TransmittanceEstimator::Ratio, random, ignored)
                   .x;
      }
      sample[i].truth = sum / reference;
    }
    double meanTruth = 0;
    for (const Ray& r : sample) meanTruth += r.truth;
    meanTruth /= double(sample.size());
    // Three rounds, alternating, each estimator's fastest kept (the error is
    // the same every round: the same random numbers).
    Measured ratio, delta;
    for (int round = 0; round < 3; ++round) {
      const Measured r = measure(media, sample, TransmittanceEstimator::Ratio, estimates, 1);
      const Measured d = measure(media, sample, TransmittanceEstimator::Delta, estimates, 2);
      if (round == 0 || r.secondsEach < ratio.secondsEach) ratio = r;
      if (round == 0 || d.secondsEach < delta.secondsEach) delta = d;
    }
    const double equalTime =
        std::sqrt((delta.mse * delta.secondsEach) / (ratio.mse * ratio.secondsEach));
    fmt::print("scene      {} (medium '{}')\n", scenePath, medium.name);
    fmt::print("rays       {} from where the density is >= 10 % of its largest, mean T {:.4f}\n",
               sample.size(), meanTruth);
    fmt::print("{:<10} {:>12} {:>14} {:>16} {:>16}\n", "estimator", "MSE", "us/estimate",
               "null collisions", "cells");
    for (const auto& [name, m] : {std::pair{"ratio", ratio}, std::pair{"delta", delta}}) {
      const double n = double(sample.size()) * estimates;
      fmt::print("{:<10} {:>12.6f} {:>14.3f} {:>16.1f} {:>16.1f}\n", name, m.mse,
                 m.secondsEach * 1e6, double(m.counts.nullCollisions) / n,
                 double(m.counts.majorantCells) / n);
    }
    fmt::print("equal-time error ratio (delta / ratio): {:.2f}\n", equalTime);
    if (equalTime < minRatio) {
      fmt::print(stderr, "transmittance_estimators: ratio {:.2f} is below --min-ratio {:.2f}\n",
                 equalTime, minRatio);
      return 1;
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "transmittance_estimators: {}\n", e.what());
    return 2;
  }
  return 0;
}
