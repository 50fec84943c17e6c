// A pinhole camera made from a named scene view and the image size.
#pragma once

#include "core/math.h"

namespace ferry {

struct CameraView;

class Camera {
 public:
  Camera(const CameraView& view, int width, int height);
  Vec3f origin() const { return origin_; }
  // Unit direction through the image-plane point (x, y) in pixels, y down.
  Vec3f direction(float x, float y) const;
  // Inverse: the image position a world direction projects to; false if behind.
  bool project(Vec3f direction, float& x, float& y) const;

 private:
  Vec3f origin_;
  Vec3f forward_, right_, up_;
  float tanHalfY_ = 0, tanHalfX_ = 0;
  int width_ = 1, height_ = 1;
};

}  // namespace ferry
