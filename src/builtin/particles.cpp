#include "builtin/particles.h"

#include <cmath>

#include "builtin/noise.h"
#include "shapes/spheres.h"

namespace ferry::builtin {
namespace {

constexpr int kClusters = 5;

// A standard normal number (Box-Muller) from two of the stream's numbers.
float gaussian(HashRng& rng) {
  const float u = 1 - rng.uniform(), v = rng.uniform();
  return std::sqrt(-2 * std::log(u)) * std::cos(2 * kPi * v);
}

}  // namespace

ScenePlan planParticles(uint64_t count, uint32_t seed) {
  ScenePlan plan;
  plan.name = "particles";
  const uint64_t n = std::max<uint64_t>(count, 1);
  const float spacing = 2.0f / std::cbrt(float(n));
  const int32_t blue = addDiffuseMaterial(plan, "particles", {0.35f, 0.55f, 0.85f});
  const int32_t grey = addDiffuseMaterial(plan, "studio", Vec3f(0.5f));

  // A floor and a backdrop, 3 out: they span the bounds (the particles stay
  // within 1.1 of the centre).
  addStudio(plan, grey, 3, -1.2f, 3);

  ShapeRecipe particles;
  particles.name = "particles";
  particles.kind = "spheres";
  particles.material = blue;
  particles.primitives = n;
  particles.bytes = n * (sizeof(Vec3f) + sizeof(float));
  particles.build = [=] {
    std::vector<Vec3f> centres(n);
    std::vector<float> radii(n);
    Vec3f clusterCentre[kClusters];
    float clusterSpread[kClusters];
    HashRng clusters(seed, 0xc1u);
    for (int c = 0; c < kClusters; ++c) {
      const float x = clusters.uniform(), y = clusters.uniform(), z = clusters.uniform();
      clusterCentre[c] = Vec3f(x, y, z) * 1.2f - Vec3f(0.6f);
      clusterSpread[c] = 0.12f + 0.2f * clusters.uniform();
    }
    for (uint64_t i = 0; i < n; ++i) {
      HashRng rng(seed, uint32_t(i), uint32_t(i >> 32));
      const int c = int(rng.uniform() * kClusters) % kClusters;
      const float gx = gaussian(rng), gy = gaussian(rng), gz = gaussian(rng);
      const Vec3f p = clusterCentre[c] + Vec3f(gx, gy, gz) * clusterSpread[c];
      centres[i] = min(max(p, Vec3f(-1)), Vec3f(1));
      radii[i] = spacing * (0.15f + 0.2f * rng.uniform());
    }
    return std::make_shared<Spheres>(std::move(centres), std::move(radii));
  };
  plan.shapes.push_back(std::move(particles));

  addStudioDaylightAndView(plan);
  return plan;
}

}  // namespace ferry::builtin
