// Direct lighting against closed forms (max depth 1, black environment):
//  - a Lambertian plane of albedo a under a sun of irradiance E at angle
//    theta from the normal: L = a E cos(theta) / pi. Exact for a sun disk of
//    any size (fully above the horizon), because the cap's cosine-weighted
//    solid angle is cos(theta) pi sin^2(r) and the sun's radiance is
//    E / (pi sin^2(r));
//  - the same plane under a square emitter of radiance Le, parallel to it:
//    L = a Le F, with F the point-to-rectangle view factor (corner formula,
//    superposed with signs for any point), averaged over each pixel the way
//    the camera jitters.
// z-tests of the image mean at significance 0.01 (Sidak over all checks),
// standard error from the per-pixel variance across frames, plus the
// half-precision rounding bound of the shadow-ray weight.
#include <gtest/gtest.h>

#include <cstdio>

#include "render/camera.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

constexpr double kAlpha = 0.01;

Scene litPlane(Vec3f albedo) {
  Scene scene;
  scene.name = "plane";
  int32_t m = scene.addMaterial(diffuseMaterial(albedo));
  // 1000 x 1000 at y = 0, normal +y: every camera ray below hits it.
  scene.addSingleInstanceMesh(makeQuad({-500, 0, 500}, {1000, 0, 0}, {0, 0, -1000}, m));
  CameraView view;
  view.from = {0.2f, 1, 0.1f};
  view.at = {0, 0, -1};
  view.fovY = 40;
  scene.views.push_back(view);
  return scene;
}

TEST(DirectLighting, LambertianPlaneUnderTheSun) {
  const Vec3f albedo{0.6f, 0.4f, 0.8f};
  const Vec3f irradiance{2, 3, 1.5f};
  struct Case {
    float thetaDegrees, angularRadius;
  };
  const Case cases[] = {{0, 0.00465f},  {30, 0.00465f}, {60, 0.00465f},
                        {80, 0.00465f}, {45, 0.05f},    {20, 0.002f}};
  const double z = twoSidedNormalQuantile(sidak(kAlpha, 3.0 * std::size(cases)));
  for (const Case& c : cases) {
    Scene scene = litPlane(albedo);
    float t = c.thetaDegrees * kPi / 180;
    SunLight sun;
    sun.direction = normalize(Vec3f{std::sin(t) * 0.6f, std::cos(t), std::sin(t) * 0.8f});
    sun.irradiance = irradiance;
    sun.angularRadius = c.angularRadius;
    scene.suns.push_back(sun);

    RenderSettings s;
    s.width = s.height = 24;
    s.samplesPerPixel = 4;
    s.maxDepth = 1;
    s.seed = 17;
    PixelStatistics stats = renderStatistics(scene, s, 4);
    EXPECT_EQ(stats.retraceMisses, 0u);
    for (int k = 0; k < 3; ++k) {
      double mean, se;
      stats.imageMean(k, mean, se);
      double expected = double(albedo[k]) * irradiance[k] * std::cos(double(t)) / std::numbers::pi;
      double bound = z * se + kHalfRelativeError * expected;
      std::printf(
          "[ sun      ] theta %4.1f r %.5f ch%d: mean %.6f +- %.2e expected %.6f (rel. diff %+.2e, "
          "allowed %.1e)\n",
          c.thetaDegrees, c.angularRadius, k, mean, se, expected, mean / expected - 1,
          bound / expected);
      EXPECT_NEAR(mean, expected, bound)
          << "theta " << c.thetaDegrees << " radius " << c.angularRadius;
    }
  }
}

// View factor from a differential area to a parallel rectangle [0, x] x [0, y]
// at height h whose corner is straight above it; odd in x and in y, so
// rectangles not above the point are sums with signs.
double cornerViewFactor(double x, double y, double h) {
  double a = x / h, b = y / h;
  double sa = std::sqrt(1 + a * a), sb = std::sqrt(1 + b * b);
  return (a / sa * std::atan(b / sa) + b / sb * std::atan(a / sb)) / (2 * std::numbers::pi);
}
double rectangleViewFactor(double px, double pz, double x0, double x1, double z0, double z1,
                           double h) {
  return cornerViewFactor(x1 - px, z1 - pz, h) - cornerViewFactor(x0 - px, z1 - pz, h) -
         cornerViewFactor(x1 - px, z0 - pz, h) + cornerViewFactor(x0 - px, z0 - pz, h);
}

Material emitterMaterial(Vec3f radiance) {
  Material emitter;
  emitter.name = "emitter";
  emitter.baseColor = Vec3f(0);
  emitter.emission = radiance;
  return emitter;
}

// Looking at the centre under the emitter from the side, under its edge,
// with a narrow view: the image spans about 0.3 units around the centre.
CameraView underTheEmitter() {
  CameraView view;
  view.from = {0.3f, 0.45f, 2.4f};
  view.at = {0.05f, 0, 0.1f};
  view.fovY = 8;
  return view;
}

TEST(DirectLighting, LambertianPlaneUnderASquareEmitter) {
  const Vec3f albedo{0.5f, 0.7f, 0.3f};
  const Vec3f le{4, 2, 6};
  const double h = 1, half = 0.5;
  Scene scene = litPlane(albedo);
  int32_t e = scene.addMaterial(emitterMaterial(le));
  // Winding gives a geometric normal of +y (away from the plane); emitters
  // are two-sided (docs/architecture.md), so the lower side emits.
  scene.addSingleInstanceMesh(makeQuad({-float(half), float(h), -float(half)},
                                       {0, 0, 2 * float(half)}, {2 * float(half), 0, 0}, e));
  const CameraView view = underTheEmitter();
  scene.views = {view};

  RenderSettings s;
  s.width = s.height = 24;
  s.samplesPerPixel = 8;
  s.maxDepth = 1;
  s.seed = 23;
  PixelStatistics stats = renderStatistics(scene, s, 8);
  EXPECT_EQ(stats.retraceMisses, 0u);

  // The expected image mean: the view factor at the plane point of each of
  // 8 x 8 sub-pixel positions, averaged (the camera jitters uniformly in the pixel).
  Camera camera(view, s.width, s.height);
  double viewFactorMean = 0;
  constexpr int kSub = 8;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x)
      for (int j = 0; j < kSub; ++j)
        for (int i = 0; i < kSub; ++i) {
          Vec3f d = camera.direction(x + (i + 0.5f) / kSub, y + (j + 0.5f) / kSub);
          ASSERT_LT(d.y, 0);
          double t = -double(view.from.y) / d.y;
          double px = view.from.x + t * d.x, pz = view.from.z + t * d.z;
          viewFactorMean += rectangleViewFactor(px, pz, -half, half, -half, half, h);
        }
  viewFactorMean /= double(s.width) * s.height * kSub * kSub;
  std::printf("[ emitter  ] mean view factor %.6f (centre: %.6f)\n", viewFactorMean,
              rectangleViewFactor(0, 0, -half, half, -half, half, h));

  const double z = twoSidedNormalQuantile(sidak(kAlpha, 3));
  for (int k = 0; k < 3; ++k) {
    double mean, se;
    stats.imageMean(k, mean, se);
    double expected = albedo[k] * le[k] * viewFactorMean;
    double bound = z * se + kHalfRelativeError * expected;
    std::printf("[ emitter  ] ch%d: mean %.6f +- %.2e expected %.6f (|z| %.2f, threshold %.2f)\n",
                k, mean, se, expected, std::abs(mean - expected) / se, z);
    EXPECT_NEAR(mean, expected, bound) << "channel " << k;
  }
}

// pbrt's area lights emit only on their front (the winding normal's side):
// facing away from the plane, the square lights nothing; facing it, it
// lights the plane exactly as a two-sided one does (bit for bit: the same
// light samples, every one on the front).
TEST(DirectLighting, OneSidedEmitterLightsOnlyItsFront) {
  auto render = [](bool facingThePlane, bool twoSided) {
    Scene scene = litPlane(Vec3f(0.5f));
    Material emitter = emitterMaterial(Vec3f(4));
    emitter.emitsBackSide = twoSided;
    const int32_t e = scene.addMaterial(emitter);
    // Edges (z, x) give a winding normal of +y, away from the plane; (x, z) of -y.
    const Vec3f corner{-0.5f, 1, -0.5f}, ex{1, 0, 0}, ez{0, 0, 1};
    scene.addSingleInstanceMesh(facingThePlane ? makeQuad(corner, ex, ez, e)
                                               : makeQuad(corner, ez, ex, e));
    scene.views = {underTheEmitter()};
    RenderSettings s;
    s.width = s.height = 16;
    s.samplesPerPixel = 4;
    s.maxDepth = 2;
    s.seed = 29;
    PixelStatistics stats = renderStatistics(scene, s, 2);
    double mean = 0, se = 0;
    stats.imageMean(0, mean, se);
    return mean;
  };
  EXPECT_EQ(render(/*facingThePlane=*/false, /*twoSided=*/false), 0.0);
  const double front = render(true, false);
  EXPECT_GT(front, 0.0);
  EXPECT_EQ(front, render(true, true));
}

}  // namespace
}  // namespace ferry
