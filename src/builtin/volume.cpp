#include "builtin/volume.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "builtin/noise.h"
#include "core/error.h"

namespace ferry::builtin {
namespace {

const Vec3f kSigmaA{1, 1, 1}, kSigmaS{24, 24, 24};
constexpr float kG = 0.4f;

// The cloud's density at p in the unit cube.
float cloudDensity(Vec3f p, uint32_t seed) {
  const Vec3f q = p * 2.0f - Vec3f(1);
  const float r = length(q);
  const float ball = smoothstep(0.95f, 0.35f, r);
  if (ball <= 0) return 0;
  const float n = fbm(q * 2.5f + Vec3f(float(seed % 97)), seed, 4);
  return std::clamp(ball * (0.55f + 0.9f * n), 0.0f, 1.0f);
}

}  // namespace

ScenePlan planVolume(int size, uint32_t seed) {
  if (size < 2 || size > 4096)
    throw InputError(fmt::format("builtin:volume: size {} must be 2 to 4096 samples a side", size));
  ScenePlan plan;
  plan.name = fmt::format("volume-{}", size);
  const uint64_t samples = uint64_t(size) * uint64_t(size) * uint64_t(size);

  const int32_t ground = addDiffuseMaterial(plan, "ground", Vec3f(0.5f));
  MeshRecipe floor;
  floor.name = "ground";
  floor.material = ground;
  floor.counts = {4, 2};
  floor.hasNormals = false;
  floor.hasUvs = false;
  floor.build = [] {
    Mesh m;
    m.positions = {{-20, -1.05f, -20}, {-20, -1.05f, 20}, {20, -1.05f, 20}, {20, -1.05f, -20}};
    m.indices = {{0, 1, 2}, {0, 2, 3}};
    return m;
  };
  plan.addSingleInstanceMesh(std::move(floor));
  addDaylight(plan, {0.5f, 1, 0.3f}, {0.25f, 0.45f, 0.9f}, {0.8f, 0.85f, 0.95f}, {0.3f, 0.3f, 0.3f},
              0.3f);

  SceneSummary::Medium summary;
  summary.name = "cloud";
  summary.kind = fmt::format("grid {}x{}x{}", size, size, size);
  summary.bytes = gridMediumBytes(size, size, size);
  summary.minDensity = 0;  // the plan's bounds; the grid made holds values within them
  summary.maxDensity = 1;
  summary.sigmaA = kSigmaA;
  summary.sigmaS = kSigmaS;
  summary.g = kG;
  plan.mediaSummary.push_back(summary);
  plan.mediumBoundaries = 1;
  plan.boundaryTriangles = 12;
  plan.boundaryBytes = meshCost(boxMesh(Box3f{{-1, -1, -1}, {1, 1, 1}}, "volume box")).total();
  plan.makeMedia = [size, seed, samples](Scene& scene) {
    std::vector<float> values(samples);
    const size_t n = size_t(size);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const auto& range) {
      for (size_t z = range.begin(); z != range.end(); ++z)
        for (size_t y = 0; y < n; ++y)
          for (size_t x = 0; x < n; ++x) {
            const Vec3f p{(float(x) + 0.5f) / float(n), (float(y) + 0.5f) / float(n),
                          (float(z) + 0.5f) / float(n)};
            values[(z * n + y) * n + x] = cloudDensity(p, seed);
          }
    });
    const Box3f box{{-1, -1, -1}, {1, 1, 1}};
    scene.media.push_back(
        gridMedium("cloud", kSigmaA, kSigmaS, kG,
                   std::make_shared<DensityGrid>(size, size, size, std::move(values)),
                   Affine3f::identity(), box));
    scene.mediumBoundaries.push_back({boxMesh(box, "volume box"), {0, kNoMedium}});
  };

  CameraView view;
  view.name = "default";
  view.from = {0, 0.6f, 4.2f};
  view.at = {0, -0.1f, 0};
  view.fovY = 40;
  plan.views.push_back(view);
  plan.bounds.extend(Vec3f(-20, -1.05f, -20));
  plan.bounds.extend(Vec3f(20, -1.05f, 20));
  return plan;
}

}  // namespace ferry::builtin
