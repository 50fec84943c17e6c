// AOVs (render/aov.h): the list's parsing, the frame buffer's signed sums,
// and the values at a first surface known in closed form: a diffuse plane
// of reflectance 0.5 facing the camera has albedo 0.5, normal +z, and each
// sample's depth is its distance to the eye; a ray that misses adds zero;
// and asking for AOVs leaves the colour bit for bit as it was.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "render/aov.h"
#include "render/render_test_util.h"

namespace ferry {
namespace {

using namespace ferry::testing;

TEST(Aovs, ListsParseInOrderAndUnknownNamesAreRefused) {
  EXPECT_TRUE(parseAovList("").empty());
  const std::vector<Aov> aovs = parseAovList("depth,albedo,normal");
  ASSERT_EQ(aovs.size(), 3u);
  EXPECT_EQ(aovs[0], Aov::Depth);
  EXPECT_EQ(aovs[1], Aov::Albedo);
  EXPECT_EQ(aovs[2], Aov::Normal);
  EXPECT_EQ(aovChannelCount(aovs), 7);
  EXPECT_EQ(aovListText(aovs), "depth,albedo,normal");
  EXPECT_EQ(aovChannelCount(parseAovList("albedo,normal,geometric-normal,depth,position,uv")), 15);
  try {
    parseAovList("albedo,colour");
    FAIL() << "an unknown name was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown AOV 'colour'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("albedo, normal"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseAovList("albedo,albedo"), InputError);
  EXPECT_THROW(parseAovList("albedo,"), InputError);
}

TEST(Aovs, SignedSumsAreExactAndClearWithTheColour) {
  FrameBuffer fb(2, 1);
  fb.setAovs({Aov::Normal, Aov::Depth});
  ASSERT_EQ(fb.aovChannels(), 4);
  SurfaceAovs a;
  a.shadingNormal = Vec3f(-0.25f, 0.5f, -1);
  a.depth = 3;
  fb.addAovs(1, a);
  fb.addAovs(1, a);
  const std::vector<int64_t>& s = fb.fixedAovSum();
  EXPECT_EQ(s[0], 0);  // pixel 0 untouched
  EXPECT_FLOAT_EQ(FrameBuffer::toLinear(s[4], 0.5), -0.25f);
  EXPECT_FLOAT_EQ(FrameBuffer::toLinear(s[5], 0.5), 0.5f);
  EXPECT_FLOAT_EQ(FrameBuffer::toLinear(s[6], 0.5), -1.0f);
  EXPECT_FLOAT_EQ(FrameBuffer::toLinear(s[7], 0.5), 3.0f);
  EXPECT_EQ(FrameBuffer::toFixedSigned(-0.25f), -FrameBuffer::toFixedSigned(0.25f));
  EXPECT_EQ(FrameBuffer::toFixedSigned(std::nanf("")), 0);
  fb.setAovs({Aov::Normal, Aov::Depth});  // the same list keeps the sums
  EXPECT_NE(fb.fixedAovSum()[7], 0);
  fb.clear();
  EXPECT_EQ(fb.fixedAovSum()[7], 0);
}

// A 200 x 200 diffuse square of reflectance 0.5 in the z = 0 plane, facing
// +z, seen from (0, 0, 5) (every pixel meets it) or from behind the camera's
// back (every ray misses).
struct PlaneRender {
  std::vector<float> aovs;  // mean per channel, channel-major within a pixel
  std::vector<Vec3f> colour;
  int channels = 0;
};

PlaneRender renderPlane(const std::vector<Aov>& aovs, int spp, bool lookAway = false) {
  Scene scene;
  scene.name = "plane";
  const int32_t m = scene.addMaterial(diffuseMaterial(Vec3f(0.5f)));
  scene.addSingleInstanceMesh(makeQuad({-100, -100, 0}, {200, 0, 0}, {0, 200, 0}, m));
  scene.environment.color = Vec3f(1);
  CameraView view;
  view.from = {0, 0, 5};
  view.at = lookAway ? Vec3f(0, 0, 10) : Vec3f(0, 0, 0);
  view.fovY = 30;
  scene.views.push_back(view);
  RenderSettings settings;
  settings.width = 12;
  settings.height = 8;
  settings.samplesPerPixel = spp;
  settings.maxDepth = 2;
  settings.aovs = aovs;
  RenderSetup setup(scene, settings);
  FrameBuffer fb(settings.imageWidth(), settings.imageHeight());
  setup.renderer->renderFrame(0, fb);
  PlaneRender out;
  out.channels = fb.aovChannels();
  out.colour = fb.sum();
  for (int64_t v : fb.fixedAovSum()) out.aovs.push_back(FrameBuffer::toLinear(v, 1.0 / spp));
  return out;
}

TEST(Aovs, ADiffusePlaneFacingTheCameraHasItsKnownValues) {
  const std::vector<Aov> all = parseAovList("albedo,normal,geometric-normal,depth,position,uv");
  const PlaneRender r = renderPlane(all, 1);
  ASSERT_EQ(r.channels, 15);
  ASSERT_EQ(r.aovs.size(), size_t(12 * 8 * 15));
  for (size_t p = 0; p < 12 * 8; ++p) {
    const float* a = &r.aovs[p * 15];
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], 0.5f, 1e-6f) << "albedo, pixel " << p;
    EXPECT_NEAR(a[3], 0, 1e-6f);  // shading normal
    EXPECT_NEAR(a[4], 0, 1e-6f);
    EXPECT_NEAR(a[5], 1, 1e-6f);
    EXPECT_NEAR(a[6], 0, 1e-6f);  // geometric normal
    EXPECT_NEAR(a[7], 0, 1e-6f);
    EXPECT_NEAR(a[8], 1, 1e-6f);
    // One sample: the depth is the distance from the eye to the position.
    const Vec3f position(a[10], a[11], a[12]);
    EXPECT_NEAR(position.z, 0, 1e-5f);
    EXPECT_NEAR(a[9], length(position - Vec3f(0, 0, 5)), 1e-5f) << "depth, pixel " << p;
    EXPECT_GE(a[9], 5 - 1e-5f);
    EXPECT_LE(a[9], 5 / std::cos(0.5f));  // within the view's half diagonal (0.45)
    // uv: (x + 100) / 200, (y + 100) / 200.
    EXPECT_NEAR(a[13], (position.x + 100) / 200, 1e-5f);
    EXPECT_NEAR(a[14], (position.y + 100) / 200, 1e-5f);
  }
  // Many samples: the mean of the same values.
  const PlaneRender many = renderPlane({Aov::Albedo, Aov::Depth}, 16);
  for (size_t p = 0; p < 12 * 8; ++p) {
    EXPECT_NEAR(many.aovs[p * 4], 0.5f, 1e-6f);
    EXPECT_GE(many.aovs[p * 4 + 3], 5 - 1e-5f);
  }
}

TEST(Aovs, RaysThatMissAddZero) {
  const PlaneRender r = renderPlane(parseAovList("albedo,normal,depth"), 4, true);
  for (float v : r.aovs) EXPECT_EQ(v, 0.0f);
}

TEST(Aovs, TheColourIsTheSameBitForBitWithOrWithoutThem) {
  const PlaneRender with = renderPlane(parseAovList("albedo,normal,depth,uv"), 4);
  const PlaneRender without = renderPlane({}, 4);
  EXPECT_EQ(without.channels, 0);
  EXPECT_TRUE(without.aovs.empty());
  EXPECT_TRUE(with.colour == without.colour);
}

// The viewer's picture of one AOV: normals as 0.5 + 0.5 n, albedo in sRGB,
// depth scaled by its range with near bright and misses black.
TEST(Aovs, PicturesShowOneAovOfSeveral) {
  const std::vector<Aov> aovs = {Aov::Albedo, Aov::Normal, Aov::Depth};
  // Two pixels, 7 floats each: albedo (3), normal (3), depth (1).
  const std::vector<float> values = {1, 0, 0.5f, 0,  0, 1, 2,   // near
                                     0, 0, 0,    -1, 0, 0, 6};  // far
  const std::vector<uint8_t> normal = aovPicture(values, aovs, Aov::Normal, 2);
  EXPECT_EQ(std::vector<uint8_t>(normal.begin(), normal.begin() + 8),
            (std::vector<uint8_t>{128, 128, 255, 255, 0, 128, 128, 255}));
  const std::vector<uint8_t> albedo = aovPicture(values, aovs, Aov::Albedo, 2);
  EXPECT_EQ(albedo[0], 255);
  EXPECT_EQ(albedo[1], 0);
  EXPECT_EQ(albedo[2], 188);  // sRGB of 0.5
  const std::vector<uint8_t> depth = aovPicture(values, aovs, Aov::Depth, 2);
  EXPECT_EQ(depth[0], 255);  // the nearest
  EXPECT_EQ(depth[4], 0);    // the farthest
  EXPECT_EQ(depth[1], depth[0]);
}

}  // namespace
}  // namespace ferry
