// The camera's pixel <-> direction maps, whole and cropped (pbrt's crop
// window), and the crop's rounding and checks.
#include "render/camera.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace ferry
