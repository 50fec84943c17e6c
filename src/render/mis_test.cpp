// Multiple importance sampling (render/path_shading.h):
//  - the light sampler's densities, recomputed where a BSDF sample lands
//    (emitterPdf, environmentPdf), equal the densities its samples carry:
//    that is what makes the two MIS weights of one light point sum to one;
//  - emitters are found from a hit's world-space corners, also through the
//    light scene (part directories) and under mirroring transforms;
//  - light samples alone, BSDF samples alone and MIS render the same mean
//    (z-tests at significance 0.01, Sidak over every comparison).
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "render/render_test_util.h"
#include "render/surface.h"
#include "scene/light_scene.h"

namespace ferry {
namespace {

using namespace ferry::testing;

constexpr double kAlpha = 0.01;

Material emitter(Vec3f radiance, bool twoSided) {
  Material m;
  m.name = "emitter";
  m.baseColor = Vec3f(0);
  m.emission = radiance;
  m.emitsBackSide = twoSided;
  return m;
}

Material roughMetal(float roughness) {
  Material m;
  m.name = "metal";
  m.baseColor = {0.9f, 0.7f, 0.5f};
  m.metallic = 1;
  m.roughness = roughness;
  return m;
}

// A floor (half diffuse, half rough metal) under a small one-sided square
// emitter facing down and an emissive sphere, in a sky of an environment
// map with one bright cell, and a sun: every kind of light, indirect light
// at max depth 3.
Scene misScene(int sphereRings) {
  Scene scene;
  scene.name = "mis";
  const int32_t diffuse = scene.addMaterial(diffuseMaterial({0.6f, 0.5f, 0.4f}));
  const int32_t metal = scene.addMaterial(roughMetal(0.25f));
  const int32_t square = scene.addMaterial(emitter({20, 16, 12}, false));
  const int32_t ball = scene.addMaterial(emitter({3, 5, 8}, true));
  scene.addSingleInstanceMesh(makeQuad({-4, 0, 4}, {4, 0, 0}, {0, 0, -8}, diffuse));
  scene.addSingleInstanceMesh(makeQuad({0, 0, 4}, {4, 0, 0}, {0, 0, -8}, metal));
  // Winding normal cross({0,0,0.6}, {0.6,0,0}) = -y: faces the floor.
  scene.addSingleInstanceMesh(makeQuad({-0.3f, 1.5f, -0.3f}, {0, 0, 0.6f}, {0.6f, 0, 0}, square));
  scene.addSingleInstanceMesh(
      makeSphere({1.2f, 0.6f, -0.8f}, 0.3f, sphereRings, 2 * sphereRings, ball));
  auto sky = std::make_shared<HdrImage>();
  sky->width = 16;
  sky->height = 8;
  sky->pixels.assign(16 * 8, Vec3f(0.2f, 0.3f, 0.5f));
  sky->pixels[2 * 16 + 5] = Vec3f(40, 30, 20);
  scene.environment.image = sky;
  scene.environment.color = Vec3f(1);
  SunLight sun;
  sun.direction = normalize(Vec3f{0.3f, 1, 0.2f});
  sun.irradiance = {1, 1, 1};
  scene.suns.push_back(sun);
  CameraView view;
  view.from = {0, 2.5f, 3.5f};
  view.at = {0, 0, -0.3f};
  view.fovY = 50;
  scene.views.push_back(view);
  return scene;
}

// Which emissive triangle of `scene` (world corners, as the shading side
// computes them) holds `point`: of those in whose plane it lies, the one it
// is deepest inside (a point near an edge is near two); false if none.
bool containingTriangle(const Scene& scene, Vec3f point, std::array<Vec3f, 3>& corners) {
  float deepest = -1e-4f;
  bool found = false;
  for (const Instance& inst : scene.instances)
    for (int32_t m : scene.objects[inst.object].meshes) {
      const Mesh& mesh = scene.meshes[m];
      if (!scene.materials[mesh.material].isEmissive()) continue;
      for (const Vec3i& tri : mesh.indices) {
        const std::array<Vec3f, 3> c{inst.transform.transformPoint(mesh.positions[tri.x]),
                                     inst.transform.transformPoint(mesh.positions[tri.y]),
                                     inst.transform.transformPoint(mesh.positions[tri.z])};
        const Vec3f n = cross(c[1] - c[0], c[2] - c[0]);
        const float area2 = length(n);
        if (std::abs(dot(point - c[0], n)) > 1e-5f * area2) continue;
        const float b1 = dot(cross(point - c[0], c[2] - c[0]), n) / (area2 * area2);
        const float b2 = dot(cross(c[1] - c[0], point - c[0]), n) / (area2 * area2);
        const float depth = std::min({b1, b2, 1 - b1 - b2});
        if (depth > deepest) {
          deepest = depth;
          corners = c;
          found = true;
        }
      }
    }
  return found;
}

void checkDensitiesAgree(int sphereRings) {
  const Scene scene = misScene(sphereRings);
  const LightSampler lights(scene);
  TestRng rng(sphereRings);
  int emitterSamples = 0, environmentSamples = 0, environmentMatches = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3f p{rng.uniform() * 6 - 3, rng.uniform() * 1.2f, rng.uniform() * 6 - 3};
    const Vec3f n = normalize(Vec3f{rng.uniform() - 0.5f, 1, rng.uniform() - 0.5f});
    LightSample ls;
    if (!lights.sample(p, n, false, rng.uniform(), {rng.uniform(), rng.uniform()}, ls)) continue;
    if (!ls.mis) continue;  // the sun
    if (std::isfinite(ls.distance)) {
      const Vec3f point = p + ls.direction * ls.distance;
      std::array<Vec3f, 3> corners;
      ASSERT_TRUE(containingTriangle(scene, point, corners)) << i;
      const uint32_t index = lights.emitterIndex(corners);
      ASSERT_NE(index, LightSampler::kNotAnEmitter) << i;
      const float pdf = lights.emitterPdf(p, index, point);
      ASSERT_NEAR(pdf / ls.pdf, 1.0f, 2e-3f) << i;
      ++emitterSamples;
    } else {
      const float pdf = lights.environmentPdf(p, ls.direction);
      // (A direction on a cell's edge may map back to its neighbour.)
      environmentMatches += std::abs(pdf / ls.pdf - 1) < 2e-3f;
      ++environmentSamples;
    }
  }
  EXPECT_GT(emitterSamples, 1000);
  EXPECT_GT(environmentSamples, 1000);
  EXPECT_GE(environmentMatches, environmentSamples * 0.998);
}

TEST(Mis, EmitterAndEnvironmentDensitiesAtTheHitEqualTheLightSamplesDensities) {
  checkDensitiesAgree(6);  // 120 + 2 emissive triangles: grouped
  checkDensitiesAgree(3);  // 24 + 2: each triangle its own candidate
}

TEST(Mis, EmittersAreFoundThroughTheLightSceneAndUnderMirroringTransforms) {
  Scene scene;
  const int32_t e = scene.addMaterial(emitter({1, 1, 1}, false));
  Mesh quad = makeQuad({-0.5f, 0, -0.5f}, {0, 0, 1}, {1, 0, 0}, e);
  quad.positions[0].x = -0.0f;  // -0 corners hash as +0
  Object object;
  object.meshes.push_back(int32_t(scene.meshes.size()));
  scene.meshes.push_back(quad);
  scene.objects.push_back(object);
  scene.instances.push_back({0, Affine3f::translate({1, 2, 3})});
  scene.instances.push_back({0, Affine3f::scale({-1, 1, 1})});  // mirrored
  scene.instances.push_back(
      {0, Affine3f::rotate(normalize(Vec3f{1, 2, 3}), 0.7f) * Affine3f::scale({2, 3, 4})});
  const LightSampler direct(scene), throughLights(lightScene(scene));
  const SurfaceTable table(scene);
  std::vector<uint32_t> found;
  for (int32_t instance = 0; instance < 3; ++instance)
    for (int32_t primitive = 0; primitive < 2; ++primitive) {
      TraceHit hit;
      hit.instance = instance;
      hit.meshSlot = 0;
      hit.primitive = primitive;
      const std::array<Vec3f, 3> corners = worldCorners(scene, table, hit);
      const uint32_t a = direct.emitterIndex(corners);
      EXPECT_NE(a, LightSampler::kNotAnEmitter);
      EXPECT_EQ(a, throughLights.emitterIndex(corners));
      // Any corner first.
      EXPECT_EQ(a, direct.emitterIndex({corners[2], corners[0], corners[1]}));
      found.push_back(a);
    }
  std::sort(found.begin(), found.end());
  EXPECT_EQ(std::unique(found.begin(), found.end()), found.end()) << "six distinct triangles";
  EXPECT_EQ(direct.emitterIndex({Vec3f(0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)}),
            LightSampler::kNotAnEmitter);
}

TEST(Mis, LightSamplesBsdfSamplesAndMisRenderTheSameMean) {
  const Scene scene = misScene(6);
  RenderSettings s;
  s.width = 32;
  s.height = 24;
  s.samplesPerPixel = 16;
  s.maxDepth = 3;
  const LightStrategy strategies[] = {LightStrategy::Mis, LightStrategy::LightSamples,
                                      LightStrategy::BsdfSamples};
  double mean[3][3], se[3][3];
  for (int i = 0; i < 3; ++i) {
    s.lightStrategy = strategies[i];
    s.seed = 101 + uint32_t(i);  // independent estimates
    Scene copy = scene;
    const PixelStatistics stats = renderStatistics(copy, s, 96);
    EXPECT_EQ(stats.retraceMisses, 0u);
    for (int k = 0; k < 3; ++k) stats.imageMean(k, mean[i][k], se[i][k]);
  }
  const double z = twoSidedNormalQuantile(sidak(kAlpha, 6));
  for (int i = 1; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const double bound =
          z * std::hypot(se[0][k], se[i][k]) + 2 * kHalfRelativeError * std::abs(mean[0][k]);
      std::printf("[ mis      ] ch%d: mis %.5f +- %.1e, %s %.5f +- %.1e (allowed %.1e)\n", k,
                  mean[0][k], se[0][k], lightStrategyName(strategies[i]), mean[i][k], se[i][k],
                  bound);
      EXPECT_NEAR(mean[i][k], mean[0][k], bound) << lightStrategyName(strategies[i]) << " ch" << k;
    }
  // The point of MIS: here, with a glossy floor under small bright lights, it
  // has the smallest error of the three (a property of this scene, measured
  // in bench/fidelity for real ones; the margins here are wide).
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(se[0][k], se[1][k]) << "ch" << k;
    EXPECT_LT(se[0][k], se[2][k]) << "ch" << k;
  }
}

}  // namespace
}  // namespace ferry
