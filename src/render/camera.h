// A pinhole camera made from a named scene view and the image size.
#pragma once

#include <cstdint>

#include "core/math.h"

namespace ferry {

struct CameraView;

class Camera {
 public:
  Camera(const CameraView& view, int width, int height);
  Vec3f origin() const { return origin_; }
  // Unit direction through the image-plane point (x, y) in pixels, y down.
  // (Inline, with the pixel-to-plane scales precomputed: it runs once per
  // camera ray.)
  Vec3f direction(float x, float y) const {
    const float sx = x * xScale_ - tanHalfX_;
    const float sy = tanHalfY_ - y * yScale_;
    return normalize(forward_ + right_ * sx + up_ * sy);
  }
  // Inverse: the image position a world direction projects to; false if behind.
  bool project(Vec3f direction, float& x, float& y) const;

  // For light tracing (a light path's vertex connected to the camera):
  // The pixel `point` projects to; false if outside the image or behind.
  bool pixelOf(Vec3f point, uint32_t& pixel) const;
  // The cosine between the viewing axis and unit `direction` from the camera.
  float cosToAxis(Vec3f direction) const { return dot(direction, forward_); }
  // The image plane's area at distance 1 (all pixels): a camera ray's
  // direction density over the whole image is 1 / (area cos^3), and the
  // importance a light path's splat carries is 1 / (area cos^4) (pbrt's
  // PerspectiveCamera::We), one light path per pixel.
  float planeArea() const { return 4 * tanHalfX_ * tanHalfY_; }

 private:
  Vec3f origin_;
  Vec3f forward_, right_, up_;
  float tanHalfY_ = 0, tanHalfX_ = 0;
  float xScale_ = 0, yScale_ = 0;  // 2 tan(half angle) / pixels
  int width_ = 1, height_ = 1;
};

}  // namespace ferry
