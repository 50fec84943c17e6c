// Mixed materials (Material::mixedWith, pbrt's mix): each shading point uses
// one material of the chain, chosen by the vertex's random numbers, so the
// image's mean is the amount-weighted mean of the materials'; chains work;
// bad links and cycles are errors.
#include <gtest/gtest.h>

#include "core/error.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

// A diffuse plane under a white sky, direct light only: each pixel's
// expected value is the albedo the mix gives.
double planeMean(Scene scene, int32_t material) {
  scene.addSingleInstanceMesh(makeQuad({-50, 0, 50}, {100, 0, 0}, {0, 0, -100}, material));
  CameraView view;
  view.from = {0, 2, 1};
  view.at = {0, 0, 0};
  view.fovY = 30;
  const PixelStatistics stats = renderUnderWhiteSky(scene, view);
  double mean, se;
  stats.imageMean(1, mean, se);
  return mean;
}

TEST(MaterialMix, TheMeanIsTheAmountWeightedMeanOfTheMaterials) {
  Scene scene;
  const int32_t dark = scene.addMaterial(diffuseMaterial(Vec3f(0.1f)));
  Material bright = diffuseMaterial(Vec3f(0.9f));
  bright.mixedWith = dark;
  bright.mixAmount = 0.25f;  // dark with probability 0.25
  const int32_t mix = scene.addMaterial(bright);
  // A cosine-sampled white sky gives exactly the albedo per sample, so the
  // only noise is the choice: the mean is within a few 1e-3 of 0.7.
  EXPECT_NEAR(planeMean(scene, mix), 0.75 * 0.9 + 0.25 * 0.1, 0.01);
  // A chain: mix -> (0.5) another mix -> (1.0) dark.
  Material middle = diffuseMaterial(Vec3f(0.5f));
  middle.mixedWith = dark;
  middle.mixAmount = 1;
  const int32_t middleIndex = scene.addMaterial(middle);
  Material top = diffuseMaterial(Vec3f(0.9f));
  top.mixedWith = middleIndex;
  top.mixAmount = 0.5f;
  const int32_t topIndex = scene.addMaterial(top);
  EXPECT_NEAR(planeMean(scene, topIndex), 0.5 * 0.9 + 0.5 * 0.1, 0.01);
}

TEST(MaterialMix, BadLinksAndCyclesAreErrors) {
  Scene scene;
  Material a = diffuseMaterial(Vec3f(0.5f));
  a.mixedWith = 5;
  scene.addMaterial(a);
  EXPECT_THROW(scene.validate(), InputError);
  scene.materials[0].mixedWith = 0;  // itself
  scene.materials[0].mixAmount = 0.5f;
  EXPECT_THROW(scene.validate(), InputError);
  scene.materials[0].mixedWith = -1;
  scene.materials[0].mixAmount = 1.5f;
  EXPECT_THROW(scene.validate(), InputError);
  scene.materials[0].mixAmount = 0;
  EXPECT_NO_THROW(scene.validate());
}

}  // namespace
}  // namespace ferry
