// White-furnace tests of the whole path tracer (camera, traversal, shading,
// light sampling, Russian roulette, frame buffer), on scenes whose image is
// known exactly:
//  - a convex diffuse object of albedo a in a uniform environment of radiance
//    1: light leaving it after one bounce never comes back, so L = a * 1
//    everywhere it is seen (and 1 where the environment is seen);
//  - a lossless object (smooth glass, a white mirror) in that environment:
//    every path leaves with throughput 1, so the image is 1 everywhere
//    (paths still inside at the depth limit aside);
//  - the inside of a closed emitter of radiance Le and albedo a: every
//    direction sees radiance L, so L = Le + a L, L = Le / (1 - a) (truncated
//    at the depth limit, a^(maxDepth + 1) / (1 - a) relative, negligible
//    here). This one exercises many bounces, roulette, and next-event
//    estimation with many emissive triangles (grouped light selection).
// Each check is a z-test of the image mean, with its standard error from the
// per-pixel variance across independent frames, at significance 0.01 with a
// Sidak correction, plus the bias that half-precision throughput may add
// (bounded, not hand-picked).
#include <gtest/gtest.h>

#include <cstdio>

#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/subsurface.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

constexpr double kAlpha = 0.01;

Scene sphereInEnvironment(const Material& material, float fovY, bool smoothNormals = false) {
  Scene scene;
  scene.name = "furnace";
  int32_t m = scene.addMaterial(material);
  scene.addSingleInstanceMesh(makeSphere({0, 0, 0}, 1, 32, 64, m, smoothNormals));
  scene.environment.color = Vec3f(1);
  CameraView view;
  view.name = "front";
  view.from = {0.3f, 0.4f, 3};  // off-axis, so no pixel ray runs along a symmetry line
  view.at = {0, 0, 0};
  view.fovY = fovY;
  scene.views.push_back(view);
  return scene;
}

// Half-precision bias bound (relative) for a path whose k-th scattering
// vertex contributes a^k: every stored throughput and the shadow weight round
// once each, so vertex k's term carries at most (k + 1) roundings of 2^-11:
// sum (k+1) a^k / sum a^k = 1 / (1 - a).
double halfBias(double albedo) {
  return kHalfRelativeError / (1 - std::min(albedo, 0.999));
}

struct Check {
  std::string what;
  double mean, standardError, expected, bias;
};

void expectAll(const std::vector<Check>& checks) {
  const double z = twoSidedNormalQuantile(sidak(kAlpha, double(checks.size())));
  for (const Check& c : checks) {
    std::printf(
        "[ furnace  ] %-36s mean %.6f +- %.6f (expected %.6f, |z| %.2f, threshold %.2f + bias "
        "%.1e)\n",
        c.what.c_str(), c.mean, c.standardError, c.expected,
        c.standardError > 0 ? std::abs(c.mean - c.expected) / c.standardError : 0.0, z, c.bias);
    EXPECT_NEAR(c.mean, c.expected, z * c.standardError + c.bias * c.expected) << c.what;
  }
}

TEST(Furnace, ConvexDiffuseSphereReturnsItsAlbedo) {
  std::vector<Check> checks;
  // Albedo 1 with a wide view (background included: camera rays that miss see
  // the environment); albedo 0.8 with a view the sphere fills (the sphere, a
  // tessellation inscribed in the unit sphere, subtends more than 19 degrees
  // from 3 units; the image diagonal half-angle is under 17).
  struct Case {
    float albedo, fovY;
  };
  for (Case c : {Case{1.0f, 60}, Case{0.8f, 24}, Case{0.3f, 24}}) {
    Scene scene = sphereInEnvironment(diffuseMaterial(Vec3f(c.albedo)), c.fovY);
    RenderSettings s;
    s.width = s.height = 32;
    s.samplesPerPixel = 4;
    s.maxDepth = 64;
    s.seed = 11;
    PixelStatistics stats = renderStatistics(scene, s, 8);
    EXPECT_EQ(stats.retraceMisses, 0u);
    for (int k = 0; k < 3; ++k) {
      double mean, se;
      stats.imageMean(k, mean, se);
      checks.push_back({"diffuse albedo " + std::to_string(c.albedo) + " ch" + std::to_string(k),
                        mean, se, c.albedo, kHalfRelativeError});
    }
    // Every pixel, not only the mean: with zero variance expected, each
    // frame's pixel value is the albedo up to rounding.
    for (int k = 0; k < 3; ++k)
      for (const MeanVariance& mv : stats.channel[k])
        ASSERT_NEAR(mv.mean, c.albedo, 2 * kHalfRelativeError) << "albedo " << c.albedo;
  }
  expectAll(checks);
}

TEST(Furnace, LosslessSpheresAreInvisible) {
  std::vector<Check> checks;
  Material glass;
  glass.name = "glass";
  glass.baseColor = Vec3f(1);
  glass.model = std::make_shared<DielectricModel>(1.5f, 0.0f);
  Material mirror;
  mirror.name = "mirror";
  mirror.baseColor = Vec3f(1);
  mirror.model = std::make_shared<ConductorModel>(0.0f);
  for (const Material& m : {glass, mirror}) {
    // Glass gets smooth normals: in a faceted glass sphere, rays entering
    // near the silhouette get trapped by total internal reflection between
    // facets (0.5% of the image at depth 64 with flat 32x64 facets), which is
    // the depth limit at work, not lost energy. The mirror stays flat: with
    // smooth normals, reflections about the shading normal that point below
    // the facet are (rightly) dropped, a known shading-normal loss.
    Scene scene = sphereInEnvironment(m, 40, m.model->name() == "dielectric");
    RenderSettings s;
    s.width = s.height = 32;
    s.samplesPerPixel = 4;
    s.maxDepth = 256;
    s.seed = 5;
    PixelStatistics stats = renderStatistics(scene, s, 8);
    EXPECT_EQ(stats.retraceMisses, 0u);
    for (int k = 0; k < 3; ++k) {
      double mean, se;
      stats.imageMean(k, mean, se);
      checks.push_back({m.name + " ch" + std::to_string(k), mean, se, 1.0, kHalfRelativeError});
    }
  }
  expectAll(checks);
}

// A subsurface sphere whose medium only scatters (chromatically, so the
// walk's spectral weights are at work): every walk leaves, so it is
// invisible too. Its walk's steps are not bounces, so a depth of 8 suffices.
TEST(Furnace, LosslessSubsurfaceIsInvisible) {
  std::vector<Check> checks;
  Material m;
  m.name = "subsurface";
  m.baseColor = Vec3f(1);
  m.model = std::make_shared<SubsurfaceModel>(1.33f, 0.0f, Vec3f(1));
  Scene scene = sphereInEnvironment(m, 40, true);
  Medium inside;
  inside.name = "inside";
  inside.sigmaS = Vec3f(2, 3, 4);
  inside.g = 0.3f;
  inside.subsurface = true;
  scene.media.push_back(inside);
  scene.meshes.back().media = MediumInterface{0, kNoMedium};
  RenderSettings s;
  s.width = s.height = 32;
  s.samplesPerPixel = 32;
  s.maxDepth = 8;
  s.seed = 5;
  PixelStatistics stats = renderStatistics(scene, s, 8);
  for (int k = 0; k < 3; ++k) {
    double mean, se;
    stats.imageMean(k, mean, se);
    checks.push_back({"subsurface ch" + std::to_string(k), mean, se, 1.0, kHalfRelativeError});
  }
  expectAll(checks);
}

TEST(Furnace, InsideAClosedEmitterRadianceIsLeOverOneMinusAlbedo) {
  // Albedo per channel; Le per channel. Enough triangles (over 64) that light
  // selection uses groups.
  const Vec3f albedo{0.5f, 0.8f, 0.2f};
  const Vec3f le{1.0f, 0.5f, 2.0f};
  Scene scene;
  scene.name = "closed emitter";
  Material m = diffuseMaterial(albedo);
  m.emission = le;
  int32_t mat = scene.addMaterial(m);
  scene.addSingleInstanceMesh(makeSphere({0, 0, 0}, 1, 16, 32, mat));
  CameraView view;
  view.from = {0.1f, 0.2f, 0.3f};
  view.at = {-0.5f, 0.1f, -1};
  view.fovY = 70;
  scene.views.push_back(view);
  {
    LightSampler lights(scene);
    ASSERT_GT(lights.emissiveTriangleCount(), 64u);
  }

  RenderSettings s;
  s.width = s.height = 32;
  s.samplesPerPixel = 4;
  s.maxDepth = 64;
  s.seed = 3;
  PixelStatistics stats = renderStatistics(scene, s, 16);
  EXPECT_EQ(stats.retraceMisses, 0u);
  std::vector<Check> checks;
  for (int k = 0; k < 3; ++k) {
    double mean, se;
    stats.imageMean(k, mean, se);
    double expected = le[k] / (1 - albedo[k]);
    checks.push_back(
        {"closed emitter ch" + std::to_string(k), mean, se, expected, halfBias(albedo[k])});
  }
  expectAll(checks);
}

}  // namespace
}  // namespace ferry
