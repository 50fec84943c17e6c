// The camera's pixel <-> direction maps, whole and cropped (pbrt's crop
// window), the crop's rounding and checks, and the thin lens.
#include "render/camera.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "scene/scene.h"

namespace ferry {
namespace {

CameraView testView() {
  CameraView v;
  v.from = {1, 2, 3};
  v.at = {0, 0, -4};
  v.up = {0, 1, 0};
  v.fovY = 50;
  return v;
}

TEST(CropWindow, RoundsAsPbrt) {
  // pbrt-v3's Film: pixel bounds from ceil(resolution x fraction).
  const FilmWindow w = filmWindow(100, 50, {0.111f, 0.5f, 0.25f, 0.999f});
  EXPECT_EQ(w.x0, 12);
  EXPECT_EQ(w.width, 50 - 12);
  EXPECT_EQ(w.y0, 13);
  EXPECT_EQ(w.height, 50 - 13);
  EXPECT_TRUE(filmWindow(100, 50, {}).whole());
  EXPECT_FALSE(w.whole());
  // Pixel (3, 2) of the image is pixel (15, 15) of the film.
  EXPECT_EQ(w.filmPixel(2 * uint32_t(w.width) + 3), 15u * 100u + 15u);
}

TEST(CropWindow, RejectsEmptyAndOutOfRangeWindows) {
  EXPECT_THROW(filmWindow(100, 50, {0.5f, 0.5f, 0, 1}), InputError);
  EXPECT_THROW(filmWindow(100, 50, {0.6f, 0.5f, 0, 1}), InputError);
  EXPECT_THROW(filmWindow(100, 50, {-0.1f, 0.5f, 0, 1}), InputError);
  EXPECT_THROW(filmWindow(100, 50, {0, 1, 0, 1.5f}), InputError);
  // Non-empty fractions that hold no pixel of this image.
  EXPECT_THROW(filmWindow(10, 10, {0.51f, 0.52f, 0, 1}), InputError);
  EXPECT_THROW(parseCropWindow("--crop", "0,1,0"), InputError);
  EXPECT_THROW(parseCropWindow("--crop", "0,1,0,x"), InputError);
  const CropWindow c = parseCropWindow("--crop", "0.1,0.9,0.2,0.7");
  EXPECT_FLOAT_EQ(c.x0, 0.1f);
  EXPECT_FLOAT_EQ(c.y1, 0.7f);
}

TEST(Camera, ACroppedCameraSeesThePartOfTheWholeImage) {
  const CameraView view = testView();
  const Camera whole(view, 64, 48);
  const FilmWindow w = filmWindow(64, 48, {0.25f, 0.75f, 0.5f, 1});
  const Camera part(view, w);
  for (float x : {0.0f, 3.5f, 31.9f})
    for (float y : {0.0f, 7.25f, 23.9f}) {
      // Directions are of film positions, whether cropped or not.
      const float fx = x + float(w.x0), fy = y + float(w.y0);
      const Vec3f a = part.direction(fx, fy);
      const Vec3f b = whole.direction(fx, fy);
      EXPECT_EQ(a, b);
      float px = 0, py = 0;
      ASSERT_TRUE(part.project(a, px, py));
      EXPECT_NEAR(px, fx, 1e-3f);
      EXPECT_NEAR(py, fy, 1e-3f);
    }
  // A point seen in the crop lands on its pixel; one outside it on none.
  uint32_t pixel = 0;
  ASSERT_TRUE(part.pixelOf(
      view.from + part.direction(5.5f + float(w.x0), 6.5f + float(w.y0)) * 3.0f, pixel));
  EXPECT_EQ(pixel, 6u * uint32_t(w.width) + 5u);
  EXPECT_FALSE(part.pixelOf(view.from + whole.direction(1.5f, 1.5f) * 3.0f, pixel));
  // The image plane's area is that of the crop's pixels: light paths, one
  // per image pixel, splat 1 / (area cos^4).
  EXPECT_NEAR(part.planeArea() / whole.planeArea(), float(w.width * w.height) / (64.0f * 48.0f),
              1e-5f);
}

// The thin lens: every ray through a film point meets the pinhole's ray on
// the focal plane; lens points fill the disk (area fractions); a point a
// lens ray reaches maps back to the ray's pixel; radius 0 is the pinhole.
TEST(Camera, AThinLensFocusesOnItsFocalPlane) {
  CameraView view = testView();
  const Camera pinhole(view, 64, 48);
  Vec3f o, d;
  pinhole.ray(10.5f, 20.5f, {0.3f, 0.8f}, o, d);
  EXPECT_EQ(o, view.from);
  EXPECT_EQ(d, pinhole.direction(10.5f, 20.5f));
  EXPECT_FALSE(pinhole.hasLens());

  view.lensRadius = 0.5f;
  view.focalDistance = 6;
  const Camera lens(view, 64, 48);
  ASSERT_TRUE(lens.hasLens());
  const Vec3f forward = normalize(view.at - view.from);
  int inner = 0, samples = 0;
  for (float u : {0.02f, 0.3f, 0.5f, 0.77f, 0.98f})
    for (float v : {0.05f, 0.41f, 0.5f, 0.66f, 0.93f}) {
      for (float x : {0.5f, 31.25f, 63.5f})
        for (float y : {0.5f, 17.75f, 47.5f}) {
          lens.ray(x, y, {u, v}, o, d);
          EXPECT_LE(length(o - view.from), 0.5f + 1e-5f);
          EXPECT_NEAR(dot(o - view.from, forward), 0, 1e-5f);  // across the axis
          // Where it meets the focal plane: on the pinhole's ray.
          const float t = (6 - dot(o - view.from, forward)) / dot(d, forward);
          const Vec3f focus = o + d * t;
          const Vec3f expected =
              view.from + pinhole.direction(x, y) * (6 / dot(pinhole.direction(x, y), forward));
          EXPECT_LT(length(focus - expected), 1e-4f * 6);
          // A point further along maps back to the pixel.
          uint32_t pixel = 0;
          ASSERT_TRUE(lens.pixelOf(o + d * (t * 0.37f), o, pixel));
          EXPECT_EQ(pixel, uint32_t(y) * 64 + uint32_t(x));
        }
      inner += length(lens.lensPoint({u, v}) - view.from) < 0.5f * std::sqrt(0.5f);
      ++samples;
    }
  // The concentric map is uniform: about half of a grid of samples lands in
  // the inner disk of half the area (a coarse check).
  EXPECT_NEAR(double(inner) / samples, 0.5, 0.2);
  // A lens needs a focal distance.
  view.focalDistance = 0;
  EXPECT_THROW(Camera(view, 64, 48), InputError);
}

}  // namespace
}  // namespace ferry
