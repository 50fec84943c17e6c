// A perspective camera, a pinhole or a thin lens, made from a named scene
// view and the image size.
#pragma once

#include <cstdint>
#include <string>

#include "core/math.h"

namespace ferry {

struct CameraView;

// pbrt's crop window: the part of the film rendered, as fractions of its
// width and height, [x0, x1) x [y0, y1), y down. The image is that part only.
struct CropWindow {
  float x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  bool whole() const { return x0 == 0 && x1 == 1 && y0 == 0 && y1 == 1; }
};

// The pixels an image holds of a film: `width` x `height` from (x0, y0) of
// a film of filmWidth x filmHeight.
struct FilmWindow {
  int filmWidth = 1, filmHeight = 1;
  int x0 = 0, y0 = 0, width = 1, height = 1;
  bool whole() const { return width == filmWidth && height == filmHeight; }
  // The film's index of the image's pixel `pixel` (random numbers are keyed
  // by it, so that a crop renders the whole image's pixels).
  uint32_t filmPixel(uint32_t pixel) const {
    const uint32_t w = uint32_t(width);
    return (pixel / w + uint32_t(y0)) * uint32_t(filmWidth) + pixel % w + uint32_t(x0);
  }
};
// The window `crop` selects, rounded as pbrt rounds it (pixel bounds from
// ceil(resolution x fraction)); InputError if it holds no pixel or the
// fractions are not 0 <= min < max <= 1.
FilmWindow filmWindow(int filmWidth, int filmHeight, const CropWindow& crop);
// "x0,x1,y0,y1" -> a crop window; throws InputError naming `flag`.
CropWindow parseCropWindow(const std::string& flag, const std::string& text);

class Camera {
 public:
  // The whole film of width x height pixels.
  Camera(const CameraView& view, int width, int height);
  // The part of the film `window` holds: pixel (x, y) of the image is pixel
  // (x0 + x, y0 + y) of the film, seen as it is in the whole film's image.
  Camera(const CameraView& view, const FilmWindow& window);
  Vec3f origin() const { return origin_; }
  // Unit direction through the point (x, y) of the film, in pixels, y down
  // (with a crop window, the image's pixel (px, py) is at px + x0, py + y0;
  // callers add the window's integer offset before the jitter, so that a
  // crop computes the very rays of the whole image).
  [[gnu::always_inline]] Vec3f direction(float x, float y) const {
    return normalize(planePoint(x, y));
  }
  // The film point (x, y) on the image plane at distance 1 ahead, from the
  // eye: direction(x, y) before it is normalized (for a caller that
  // normalizes anyway, as a path's direction encoding does: a pinhole camera
  // path). Inline, with the pixel-to-plane scales precomputed: it runs once
  // per camera ray.
  [[gnu::always_inline]] Vec3f planePoint(float x, float y) const {
    const float sx = x * xScale_ - tanHalfX_;
    const float sy = tanHalfY_ - y * yScale_;
    return forward_ + right_ * sx + up_ * sy;
  }
  // Inverse: the film position a world direction projects to; false if behind.
  bool project(Vec3f direction, float& x, float& y) const;

  // The thin lens (CameraView::lensRadius): a camera ray leaves the lens
  // point `uLens` ([0, 1)^2, mapped concentrically onto the disk) picks,
  // towards where the pinhole's ray through film point (x, y) meets the
  // focal plane. A pinhole's ray is (origin(), direction(x, y)).
  bool hasLens() const { return lensRadius_ > 0; }
  Vec3f lensPoint(Vec2f uLens) const;
  void ray(float x, float y, Vec2f uLens, Vec3f& rayOrigin, Vec3f& rayDirection) const;

  // For light tracing (a light path's vertex connected to the camera):
  // The image pixel `point` projects to; false if outside the image (the
  // window) or behind.
  bool pixelOf(Vec3f point, uint32_t& pixel) const;
  // The same for the ray from the lens point `lens` to `point`: the pixel
  // whose camera rays from `lens` pass through `point`.
  bool pixelOf(Vec3f point, Vec3f lens, uint32_t& pixel) const;
  // The cosine between the viewing axis and unit `direction` from the camera.
  float cosToAxis(Vec3f direction) const { return dot(direction, forward_); }
  // The image plane's area at distance 1 (the image's pixels, within the
  // window): a camera ray's direction density over the image is
  // 1 / (area cos^3), and the importance a light path's splat carries is
  // 1 / (area cos^4) (pbrt's PerspectiveCamera::We), one light path per
  // pixel of the image. (pbrt-v3 takes the whole film's area even when
  // cropped, which darkens light tracing there by the crop's fraction.)
  float planeArea() const { return xScale_ * float(width_) * yScale_ * float(height_); }

 private:
  Vec3f origin_;
  Vec3f forward_, right_, up_;
  float tanHalfY_ = 0, tanHalfX_ = 0;  // of the whole film
  float xScale_ = 0, yScale_ = 0;      // 2 tan(half angle) / film pixels
  int x0_ = 0, y0_ = 0;                // the window's corner in the film
  int width_ = 1, height_ = 1;         // the image
  float lensRadius_ = 0, focalDistance_ = 1;
};

}  // namespace ferry
