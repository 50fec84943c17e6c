// Multiple importance sampling (render/path_shading.h):
//  - the light sampler's densities, recomputed where a BSDF sample lands
//    (emitterPdf, environmentPdf), equal the densities its samples carry:
//    that is what makes the two MIS weights of one light point sum to one;
//  - emitters are found from a hit's world-space corners, also through the
//    light scene (part directories) and under mirroring transforms;
//  - light samples alone, BSDF samples alone, MIS, and MIS with light paths
//    (each heuristic, each light choice) render the same mean (z-tests at
//    significance 0.01, Sidak over every comparison); light paths through a
//    rough glass shell around a lamp too (the adjoint of a rough
//    dielectric), with less noise.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "material/models/conductor.h"
#include "material/models/dielectric.h"
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
  m.model = std::make_shared<ConductorModel>(roughness);
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

void checkDensitiesAgree(int sphereRings, LightChoice choice) {
  const Scene scene = misScene(sphereRings);
  const LightSampler lights(scene, choice);
  TestRng rng(sphereRings);
  int emitterSamples = 0, environmentSamples = 0, environmentMatches = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3f p{rng.uniform() * 6 - 3, rng.uniform() * 1.2f, rng.uniform() * 6 - 3};
    const Vec3f n = normalize(Vec3f{rng.uniform() - 0.5f, 1, rng.uniform() - 0.5f});
    LightSample ls;
    // Half of them for a surface that only reflects (`facing`): the emitters'
    // and the environment map's densities are the same either way.
    if (!lights.sample(p, Frame(n), false, rng.uniform(), {rng.uniform(), rng.uniform()}, ls,
                       i % 2 ? n : Vec3f(0)))
      continue;
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
  for (const LightChoice choice : {LightChoice::Near, LightChoice::Power}) {
    checkDensitiesAgree(6, choice);  // 120 + 2 emissive triangles: grouped
    checkDensitiesAgree(3, choice);  // 24 + 2: each triangle its own candidate
  }
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
      hit.slot = 0;
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

// A diffuse floor (y = 0) under a one-sided 1x1 lamp at y = 1 (radiance 4),
// placed with its winding facing up (+y) or down, instanced under
// Scale(-1, 1, 1) or the identity; `sampledOnBackSide` as pbrt-v3's
// mirrored emitters (Material::lightSampledOnBackSide).
Scene floorUnderLamp(bool sampledOnBackSide, bool facingUp, bool mirroring) {
  Scene scene;
  const int32_t floor = scene.addMaterial(diffuseMaterial(Vec3f(0.5f)));
  Material e = emitter({4, 4, 4}, false);
  e.lightSampledOnBackSide = sampledOnBackSide;
  const int32_t light = scene.addMaterial(e);
  scene.addSingleInstanceMesh(makeQuad({-2, 0, 2}, {4, 0, 0}, {0, 0, -4}, floor));
  Object object;
  object.meshes.push_back(int32_t(scene.meshes.size()));
  scene.meshes.push_back(facingUp ? makeQuad({-0.5f, 1, 0.5f}, {1, 0, 0}, {0, 0, -1}, light)
                                  : makeQuad({-0.5f, 1, 0.5f}, {0, 0, -1}, {1, 0, 0}, light));
  scene.objects.push_back(object);
  scene.instances.push_back({int32_t(scene.objects.size() - 1),
                             mirroring ? Affine3f::scale({-1, 1, 1}) : Affine3f::identity()});
  return scene;
}

// pbrt-v3 under a mirror (Material::lightSampledOnBackSide): rays see the
// emitter on its hit side while light samples leave the other side. A
// mirrored quad whose hit side faces up (object winding +y) over a floor:
// seen emitting from above either way; the floor below is lit only with the
// flag, and then by light samples alone (BSDF rays meet the dark side).
TEST(Mis, LightSampledOnBackSideLeavesTheSideRaysDoNotSee) {
  for (const bool flag : {false, true}) {
    const Scene scene = floorUnderLamp(flag, true, true);

    const LightSampler lights(scene);
    LightSample below, above;
    const bool fromBelow = lights.sample({0, 0, 0}, {0, 1, 0}, false, 0.5f, {0.5f, 0.5f}, below) &&
                           below.pdf > 0 && maxComponent(below.radiance) > 0;
    const bool fromAbove = lights.sample({0, 2, 0}, {0, -1, 0}, false, 0.5f, {0.5f, 0.5f}, above) &&
                           above.pdf > 0 && maxComponent(above.radiance) > 0;
    EXPECT_EQ(fromBelow, flag);
    EXPECT_EQ(fromAbove, !flag);

    RenderSettings s;
    s.width = s.height = 16;
    s.samplesPerPixel = 4;
    s.maxDepth = 1;
    auto meanOf = [&](const CameraView& view) {
      Scene copy = scene;
      copy.views = {view};
      RenderSetup setup(copy, s);
      double sum = 0;
      const std::vector<Vec3f> pixels = setup.frameMean(0);
      for (const Vec3f& p : pixels) sum += p.y;
      return sum / double(pixels.size());
    };
    CameraView top;  // the quad fills the view: its radiance
    top.from = {0, 1.5f, 0};
    top.at = {0, 0, 0};
    top.up = {0, 0, -1};
    top.fovY = 40;
    EXPECT_NEAR(meanOf(top), 4.0, 1e-3) << flag;
    CameraView side;  // the floor under the quad
    side.from = {0, 0.4f, 2.5f};
    side.at = {0, 0, 0};
    side.fovY = 30;
    if (flag)
      EXPECT_GT(meanOf(side), 0.02);
    else
      EXPECT_EQ(meanOf(side), 0.0);
  }
}

// Under pbrt-v3's mirrored emitters a BSDF sample meets the dark side, so
// what the image loses is the BSDF strategy's MIS weight: more with the
// balance heuristic than with the power heuristic (pbrt-v3's bdpt weighs by
// balance; docs/fidelity.md). For a consistent emitter the two agree.
TEST(Mis, TheHeuristicDecidesWhatAMirroredEmittersDarkSideLoses) {
  for (const bool mirrored : {false, true}) {
    // Consistent: faces the floor. Mirrored: rays from the floor see its
    // dark side while its light samples leave towards the floor.
    Scene scene = mirrored ? floorUnderLamp(true, true, true) : floorUnderLamp(false, false, false);
    CameraView side;  // the floor under the quad
    side.from = {0, 0.4f, 2.5f};
    side.at = {0, 0, 0};
    side.fovY = 30;
    scene.views = {side};
    RenderSettings s;
    s.width = s.height = 16;
    s.samplesPerPixel = 64;
    s.maxDepth = 1;
    double mean[2];
    for (const MisHeuristic h : {MisHeuristic::Power, MisHeuristic::Balance}) {
      s.misHeuristic = h;
      RenderSetup setup(scene, s);
      double sum = 0;
      const std::vector<Vec3f> pixels = setup.frameMean(0);
      for (const Vec3f& p : pixels) sum += p.y;
      mean[h == MisHeuristic::Balance] = sum / double(pixels.size());
    }
    std::printf("[ mis      ] %s emitter: power heuristic %.4f, balance %.4f\n",
                mirrored ? "mirrored" : "consistent", mean[0], mean[1]);
    ASSERT_GT(mean[0], 0.02);
    if (mirrored)
      EXPECT_LT(mean[1], 0.95 * mean[0]);
    else
      EXPECT_NEAR(mean[1], mean[0], 0.03 * mean[0]);
  }
}

// Light paths start where sampleEmission puts them: each emissive triangle
// chosen in proportion to its power, the densities it reports equal to the
// ones MIS recomputes (emissionPositionPdf), the direction cosine-weighted
// on the emitting side (either side of a two-sided emitter, half each).
TEST(Mis, EmissionSamplesFollowPowerAndCarryTheirDensities) {
  const Scene scene = misScene(4);
  const LightSampler lights(scene);
  ASSERT_GT(lights.emissiveTriangleCount(), 2u);
  std::vector<int> chosen(lights.emissiveTriangleCount(), 0);
  int backSide = 0, twoSidedSamples = 0;
  constexpr int kSamples = 20000;
  for (int i = 0; i < kSamples; ++i) {
    const RandomStream r(RandomKey{uint32_t(i), 0, 0, 5});
    EmissionSample e;
    ASSERT_TRUE(lights.sampleEmission(r(RandomDim::LightSelect),
                                      {r(RandomDim::LightSampleU), r(RandomDim::LightSampleV)},
                                      {r(RandomDim::BsdfU), r(RandomDim::BsdfV)}, e));
    ++chosen[e.emitter];
    EXPECT_FLOAT_EQ(e.pdfPosition, lights.emissionPositionPdf(e.emitter));
    const float cosine = dot(e.direction, e.normal);
    ASSERT_GT(cosine, 0);
    const float perCosine = lights.emitsBothSides(e.emitter) ? 0.5f / kPi : 1 / kPi;
    EXPECT_NEAR(e.pdfDirection, cosine * perCosine, 1e-5f);
    if (lights.emitsBothSides(e.emitter)) {
      ++twoSidedSamples;
      // The sphere's triangles wind outwards: the back side is inside.
      backSide += dot(e.normal, e.position - Vec3f{1.2f, 0.6f, -0.8f}) < 0;
    }
  }
  // Selection in proportion to power (luminance times area): the square's
  // share of the samples against its share of the power.
  double squarePower = 0, allPower = 0;
  for (const Mesh& mesh : scene.meshes) {
    const Material& m = scene.materials[size_t(mesh.material)];
    if (!m.isEmissive()) continue;
    for (const Vec3i& t : mesh.indices) {
      const Vec3f p0 = mesh.positions[t.x], p1 = mesh.positions[t.y], p2 = mesh.positions[t.z];
      const double power = luminance(m.emission) * 0.5 * length(cross(p1 - p0, p2 - p0));
      allPower += power;
      if (!m.emitsBackSide) squarePower += power;
    }
  }
  int squareCount = 0;
  for (size_t t = 0; t < chosen.size(); ++t)
    if (!lights.emitsBothSides(uint32_t(t))) squareCount += chosen[t];
  const double p = squarePower / allPower;
  EXPECT_NEAR(double(squareCount) / kSamples, p, 4 * std::sqrt(p * (1 - p) / kSamples));
  EXPECT_GT(twoSidedSamples, 0);
  EXPECT_NEAR(double(backSide) / twoSidedSamples, 0.5, 0.05);
}

TEST(Mis, LightSamplesBsdfSamplesMisAndLightPathsRenderTheSameMean) {
  const Scene scene = misScene(6);
  RenderSettings s;
  s.width = 32;
  s.height = 24;
  s.samplesPerPixel = 16;
  s.maxDepth = 3;
  struct Estimator {
    LightStrategy strategy;
    bool lightPaths;
    const char* name;
    MisHeuristic heuristic = MisHeuristic::Power;
    LightChoice choice = LightChoice::Near;
  };
  const Estimator estimators[] = {
      {LightStrategy::Mis, false, "mis"},
      {LightStrategy::LightSamples, false, "light"},
      {LightStrategy::BsdfSamples, false, "bsdf"},
      {LightStrategy::Mis, true, "mis+light paths"},
      {LightStrategy::Mis, false, "mis, balance", MisHeuristic::Balance},
      {LightStrategy::Mis, true, "mis+light paths, balance, by power", MisHeuristic::Balance,
       LightChoice::Power},
      {LightStrategy::Mis, false, "mis, by power", MisHeuristic::Power, LightChoice::Power}};
  constexpr int kEstimators = 7;
  double mean[kEstimators][3], se[kEstimators][3];
  for (int i = 0; i < kEstimators; ++i) {
    s.lightStrategy = estimators[i].strategy;
    s.lightPaths = estimators[i].lightPaths;
    s.misHeuristic = estimators[i].heuristic;
    s.lightChoice = estimators[i].choice;
    s.seed = 101 + uint32_t(i);  // independent estimates
    Scene copy = scene;
    const PixelStatistics stats = renderStatistics(copy, s, 96);
    EXPECT_EQ(stats.retraceMisses, 0u);
    for (int k = 0; k < 3; ++k) stats.imageMean(k, mean[i][k], se[i][k]);
  }
  const double z = twoSidedNormalQuantile(sidak(kAlpha, 3 * (kEstimators - 1)));
  for (int i = 1; i < kEstimators; ++i)
    for (int k = 0; k < 3; ++k) {
      const double bound =
          z * std::hypot(se[0][k], se[i][k]) + 2 * kHalfRelativeError * std::abs(mean[0][k]);
      std::printf("[ mis      ] ch%d: mis %.5f +- %.1e, %s %.5f +- %.1e (allowed %.1e)\n", k,
                  mean[0][k], se[0][k], estimators[i].name, mean[i][k], se[i][k], bound);
      EXPECT_NEAR(mean[i][k], mean[0][k], bound) << estimators[i].name << " ch" << k;
    }
  // The point of MIS: here, with a glossy floor under small bright lights, it
  // has the smallest error of the first three (a property of this scene,
  // measured in bench/fidelity for real ones; the margins here are wide).
  for (int k = 0; k < 3; ++k) {
    EXPECT_LT(se[0][k], se[1][k]) << "ch" << k;
    EXPECT_LT(se[0][k], se[2][k]) << "ch" << k;
  }
}

// Camera paths alone and with light paths, each over `frames` frames of
// `s` (the seeds `seed` and `seed + 1`): per channel, the image means and
// their standard errors, [0] without light paths, [1] with; the means are
// checked equal (z-test at kAlpha, Sidak over the channels) and printed
// under `label`.
struct WithAndWithoutLightPaths {
  double mean[2][3], se[2][3];
};
WithAndWithoutLightPaths compareLightPaths(const Scene& scene, RenderSettings s, int frames,
                                           uint32_t seed, const char* label) {
  WithAndWithoutLightPaths r;
  for (int i = 0; i < 2; ++i) {
    s.lightPaths = i == 1;
    s.seed = seed + uint32_t(i);
    Scene copy = scene;
    const PixelStatistics stats = renderStatistics(copy, s, frames);
    for (int k = 0; k < 3; ++k) stats.imageMean(k, r.mean[i][k], r.se[i][k]);
  }
  const double z = twoSidedNormalQuantile(sidak(kAlpha, 3));
  for (int k = 0; k < 3; ++k) {
    const double bound =
        z * std::hypot(r.se[0][k], r.se[1][k]) + 2 * kHalfRelativeError * std::abs(r.mean[0][k]);
    std::printf(
        "[ %-8s ] ch%d: camera paths %.5f +- %.1e, with light paths %.5f +- %.1e "
        "(allowed %.1e)\n",
        label, k, r.mean[0][k], r.se[0][k], r.mean[1][k], r.se[1][k], bound);
    EXPECT_NEAR(r.mean[1][k], r.mean[0][k], bound) << label << " ch" << k;
  }
  return r;
}

// Through a thin lens (render/camera.h) light paths connect to a point on
// the lens: the mean stays that of camera paths alone.
TEST(Mis, LightPathsThroughAThinLensRenderTheSameMean) {
  Scene scene = misScene(4);
  scene.views[0].lensRadius = 0.2f;
  scene.views[0].focalDistance = 2.5f;
  RenderSettings s;
  s.width = 24;
  s.height = 18;
  s.samplesPerPixel = 8;
  s.maxDepth = 2;
  compareLightPaths(scene, s, 48, 201, "lens");
}

// A lamp inside a frosted (rough dielectric) glass shell above a floor: the
// floor's light comes through the glass, which light samples cannot cross.
// Light paths cross it from the lamp's side; the mean must not change (the
// light path's adjoint of the rough dielectric, the MIS weights of all three
// strategies through refractions), and the noise must fall.
Scene lampInFrostedGlass() {
  Scene scene;
  scene.name = "frosted lamp";
  const int32_t floor = scene.addMaterial(diffuseMaterial({0.7f, 0.6f, 0.5f}));
  scene.addSingleInstanceMesh(makeQuad({-4, 0, 4}, {8, 0, 0}, {0, 0, -8}, floor));
  Material frosted;
  frosted.name = "frosted";
  frosted.baseColor = Vec3f(1);
  frosted.model = std::make_shared<DielectricModel>(1.5f, 0.4f);
  scene.addSingleInstanceMesh(
      makeSphere({0, 1.2f, 0}, 0.5f, 16, 32, scene.addMaterial(frosted), true));
  scene.addSingleInstanceMesh(
      makeSphere({0, 1.2f, 0}, 0.15f, 8, 16, scene.addMaterial(emitter({40, 30, 20}, false))));
  CameraView view;
  view.from = {0, 2.2f, 3.2f};
  view.at = {0, 0.4f, 0};
  view.fovY = 55;
  scene.views.push_back(view);
  return scene;
}

TEST(Mis, LightPathsThroughRoughGlassKeepTheMeanAndLowerTheNoise) {
  const Scene scene = lampInFrostedGlass();
  RenderSettings s;
  s.width = 24;
  s.height = 18;
  s.samplesPerPixel = 8;
  s.maxDepth = 4;
  const WithAndWithoutLightPaths r = compareLightPaths(scene, s, 64, 7, "frosted");
  for (int k = 0; k < 3; ++k) EXPECT_LT(r.se[1][k], r.se[0][k]) << "ch" << k;
}

}  // namespace
}  // namespace ferry
