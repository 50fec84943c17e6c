// A tabulated (pbrt-v3 fourier) material in a render, not only as a lobe:
// a plane of paint.bsdf under a white sky, direct light only, seen from one
// direction through a narrow camera, renders the table's directional albedo
// for that direction (estimated independently from the BSDF's own samples).
// Checks the wiring from a material's FourierModel through shading, the frame's
// orientation and the light samples' use of eval().
#include <gtest/gtest.h>

#include <array>
#include <filesystem>

#include "io/pbrt/fourier_bsdf_file.h"
#include "material/bsdf.h"
#include "material/models/fourier.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

// A 100 x 100 plane of paint.bsdf facing +y; false if the table is not there.
bool paintedPlane(Scene& scene) {
  const std::filesystem::path path =
      std::filesystem::path(FERRY_SHARED_SCENES) / "breakfast" / "bsdfs" / "paint.bsdf";
  if (!std::filesystem::exists(path)) return false;
  scene.bsdfTables.push_back(readFourierBsdfFile(path.string()));
  Material paint = diffuseMaterial(Vec3f(0.5f));
  paint.model = std::make_shared<FourierModel>(0);
  const int32_t m = scene.addMaterial(paint);
  scene.addSingleInstanceMesh(makeQuad({-50, 0, 50}, {100, 0, 0}, {0, 0, -100}, m));
  return true;
}

// The image of the plane under the white sky against the BSDF's directional
// albedo for `wo` (the mean of its sampled weights on wo's side), per
// channel (z-tests at 0.01, Sidak over the channels); the image's means.
std::array<double, 3> expectTheAlbedo(const PixelStatistics& stats, const Bsdf& bsdf, Vec3f wo,
                                      uint32_t seed, const char* label) {
  TestRng rng(seed);
  MeanVariance albedo[3];
  for (int i = 0; i < 400000; ++i) {
    BsdfSample s;
    const bool ok = bsdf.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, s);
    for (int k = 0; k < 3; ++k) albedo[k].add(ok && s.wi.z * wo.z > 0 ? s.weight[k] : 0.0);
  }
  const double z = twoSidedNormalQuantile(sidak(0.01, 3));
  std::array<double, 3> means{};
  for (int k = 0; k < 3; ++k) {
    double se;
    stats.imageMean(k, means[size_t(k)], se);
    const double bound =
        z * std::hypot(se, albedo[k].standardError()) + 2 * kHalfRelativeError * albedo[k].mean;
    std::printf("[ fourier  ] ch%d: %s: render %.5f +- %.1e, albedo %.5f +- %.1e\n", k, label,
                means[size_t(k)], se, albedo[k].mean, albedo[k].standardError());
    EXPECT_NEAR(means[size_t(k)], albedo[k].mean, bound) << label << " ch" << k;
  }
  return means;
}

TEST(FourierRender, APaintedPlaneUnderAWhiteSkyShowsTheTablesAlbedo) {
  Scene scene;
  if (!paintedPlane(scene)) GTEST_SKIP() << "paint.bsdf is not available";
  // Looking down at 50 degrees from the normal, 1-degree field of view.
  const float theta = 50 * kPi / 180;
  CameraView view;
  view.from = {0, 10 * std::cos(theta), 10 * std::sin(theta)};
  view.at = {0, 0, 0};
  view.fovY = 1;
  const PixelStatistics stats = renderUnderWhiteSky(scene, view);

  // The albedo for wo = the direction to the camera, in the shading frame
  // (z the normal), over the upper hemisphere.
  const std::array<double, 3> means = expectTheAlbedo(
      stats, fourierBsdf(*scene.bsdfTables[0]), {0, std::sin(theta), std::cos(theta)}, 3, "above");
  for (int k = 0; k < 3; ++k) EXPECT_GT(means[size_t(k)], 0.05) << k;
}

// paint.bsdf's two sides differ (a glossy coat of albedo about 0.4 on top, a
// Lambertian 0.6 beneath): seen from below its normal, the plane shows the
// table's bottom, as pbrt-v3 reads it in the shading frame.
TEST(FourierRender, APaintedPlaneSeenFromBelowShowsTheTablesBottom) {
  Scene scene;
  if (!paintedPlane(scene)) GTEST_SKIP() << "paint.bsdf is not available";
  ASSERT_TRUE(scene.bsdfTables[0]->hasBackSide);
  const float theta = 50 * kPi / 180;
  CameraView view;  // below the plane, 50 degrees from its (downward) back
  view.from = {0, -10 * std::cos(theta), 10 * std::sin(theta)};
  view.at = {0, 0, 0};
  view.fovY = 1;
  const PixelStatistics stats = renderUnderWhiteSky(scene, view);
  // The bottom's albedo for this wo (below: wo.z < 0).
  const std::array<double, 3> means =
      expectTheAlbedo(stats, fourierBsdf(*scene.bsdfTables[0]),
                      {0, std::sin(theta), -std::cos(theta)}, 5, "from below");
  // The Lambertian bottom, not the coat's 0.4.
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(means[size_t(k)], 0.6, 0.03) << k;
}

}  // namespace
}  // namespace ferry
