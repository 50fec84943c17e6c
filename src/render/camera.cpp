#include "render/camera.h"

#include <algorithm>
#include <cmath>

#include "scene/scene.h"

namespace ferry {

Camera::Camera(const CameraView& view, int width, int height)
    : origin_(view.from), width_(width), height_(height) {
  forward_ = normalize(view.at - view.from);
  Vec3f upHint = view.up;
  if (length(cross(forward_, upHint)) < 1e-6f)
    upHint = std::abs(forward_.y) < 0.9f ? Vec3f(0, 1, 0) : Vec3f(0, 0, 1);
  right_ = normalize(cross(forward_, upHint));
  up_ = cross(right_, forward_);
  // A left-handed (pbrt) camera sees the same world mirrored left to right.
  if (view.leftHanded) right_ = -right_;
  tanHalfY_ = std::tan(0.5f * view.fovY * kPi / 180.0f);
  tanHalfX_ = tanHalfY_ * float(width) / float(height);
  xScale_ = 2 * tanHalfX_ / float(width);
  yScale_ = 2 * tanHalfY_ / float(height);
}

bool Camera::project(Vec3f d, float& x, float& y) const {
  float z = dot(d, forward_);
  if (z <= 0) return false;
  float sx = dot(d, right_) / z / tanHalfX_;
  float sy = dot(d, up_) / z / tanHalfY_;
  x = (sx + 1) * 0.5f * width_;
  y = (1 - sy) * 0.5f * height_;
  return true;
}

bool Camera::pixelOf(Vec3f point, uint32_t& pixel) const {
  float x, y;
  if (!project(point - origin_, x, y)) return false;
  if (!(x >= 0 && y >= 0 && x < float(width_) && y < float(height_))) return false;
  const uint32_t px = std::min(uint32_t(x), uint32_t(width_ - 1));
  const uint32_t py = std::min(uint32_t(y), uint32_t(height_ - 1));
  pixel = py * uint32_t(width_) + px;
  return true;
}

}  // namespace ferry
