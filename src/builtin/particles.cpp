#include "builtin/particles.h"

#include <cmath>

#include "core/random.h"
#include "shapes/spheres.h"

namespace ferry::builtin {
namespace {

constexpr int kClusters = 5;

float unit(uint32_t seed, uint64_t i, uint32_t dim) {
  const uint32_t h =
      hashCombine(hashCombine(hashCombine(seed, uint32_t(i)), uint32_t(i >> 32)), dim);
  return (float(h >> 8) + 0.5f) * (1.0f / 16777216.0f);
}

// A standard normal number (Box-Muller) from two of particle i's numbers.
float gaussian(uint32_t seed, uint64_t i, uint32_t dim) {
  const float u = unit(seed, i, dim), v = unit(seed, i, dim + 1);
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
  MeshRecipe studio;
  studio.name = "studio";
  studio.material = grey;
  studio.counts = {6, 4};
  studio.hasNormals = false;
  studio.hasUvs = false;
  studio.build = [] {
    Mesh m;
    m.positions = {{-3, -1.2f, 3},  {3, -1.2f, 3}, {3, -1.2f, -3},
                   {-3, -1.2f, -3}, {3, 3, -3},    {-3, 3, -3}};
    m.indices = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}, {3, 4, 5}};
    return m;
  };
  plan.addSingleInstanceMesh(std::move(studio));

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
    for (int c = 0; c < kClusters; ++c) {
      clusterCentre[c] =
          Vec3f(unit(seed, c, 90), unit(seed, c, 91), unit(seed, c, 92)) * 1.2f - Vec3f(0.6f);
      clusterSpread[c] = 0.12f + 0.2f * unit(seed, c, 93);
    }
    for (uint64_t i = 0; i < n; ++i) {
      const int c = int(unit(seed, i, 0) * kClusters) % kClusters;
      Vec3f p = clusterCentre[c] +
                Vec3f(gaussian(seed, i, 1), gaussian(seed, i, 3), gaussian(seed, i, 5)) *
                    clusterSpread[c];
      p = min(max(p, Vec3f(-1)), Vec3f(1));
      centres[i] = p;
      radii[i] = spacing * (0.15f + 0.2f * unit(seed, i, 7));
    }
    return std::make_shared<Spheres>(std::move(centres), std::move(radii));
  };
  plan.shapes.push_back(std::move(particles));

  addDaylight(plan, {0.6f, 1, 0.8f}, {0.25f, 0.45f, 0.9f}, {0.8f, 0.85f, 0.95f}, {0.3f, 0.3f, 0.3f},
              0.3f);
  CameraView view;
  view.name = "default";
  view.from = {0, 0.8f, 4.2f};
  view.at = {0, 0, 0};
  view.fovY = 40;
  plan.views.push_back(view);
  plan.bounds.extend(Vec3f(-3, -1.2f, -3));
  plan.bounds.extend(Vec3f(3, 3, 3));
  return plan;
}

}  // namespace ferry::builtin
