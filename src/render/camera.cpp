#include "render/camera.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "core/error.h"
#include "core/number_list.h"
#include "scene/scene.h"

namespace ferry {

FilmWindow filmWindow(int filmWidth, int filmHeight, const CropWindow& crop) {
  if (!isCropWindow(crop.x0, crop.x1, crop.y0, crop.y1))
    throw InputError(
        fmt::format("crop window {},{},{},{}: expected fractions x0,x1,y0,y1 of the "
                    "image with 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1",
                    crop.x0, crop.x1, crop.y0, crop.y1));
  FilmWindow w;
  w.filmWidth = filmWidth;
  w.filmHeight = filmHeight;
  // pbrt-v3's Film: croppedPixelBounds from ceil(fullResolution x fraction),
  // the product in float as pbrt forms it (600 x 0.8f is 480 in float, 481
  // in double).
  auto bound = [](int resolution, float fraction) {
    return std::clamp(int(std::ceil(float(resolution) * fraction)), 0, resolution);
  };
  w.x0 = bound(filmWidth, crop.x0);
  w.y0 = bound(filmHeight, crop.y0);
  w.width = bound(filmWidth, crop.x1) - w.x0;
  w.height = bound(filmHeight, crop.y1) - w.y0;
  if (w.width < 1 || w.height < 1)
    throw InputError(fmt::format("crop window {},{},{},{} holds no pixel of the {}x{} image",
                                 crop.x0, crop.x1, crop.y0, crop.y1, filmWidth, filmHeight));
  return w;
}

CropWindow parseCropWindow(const std::string& flag, const std::string& text) {
  float v[4];
  if (!parseNumberList(text, v))
    throw InputError(fmt::format("{} '{}': expected four numbers x0,x1,y0,y1", flag, text));
  const CropWindow crop{v[0], v[1], v[2], v[3]};
  try {
    filmWindow(1 << 20, 1 << 20, crop);  // the fractions' checks, before any image is made
  } catch (const InputError& e) {
    throw InputError(fmt::format("{} {}", flag, e.what()));
  }
  return crop;
}

Camera::Camera(const CameraView& view, int width, int height)
    : Camera(view, FilmWindow{width, height, 0, 0, width, height}) {}

Camera::Camera(const CameraView& view, const FilmWindow& window)
    : origin_(view.from),
      x0_(window.x0),
      y0_(window.y0),
      width_(window.width),
      height_(window.height) {
  const int width = window.filmWidth, height = window.filmHeight;
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
  if (view.lensRadius > 0) {
    if (!(view.focalDistance > 0) || !std::isfinite(view.focalDistance) ||
        !std::isfinite(view.lensRadius))
      throw InputError(
          fmt::format("camera: lens radius {} needs a positive, finite focal "
                      "distance (it is {})",
                      view.lensRadius, view.focalDistance));
    lensRadius_ = view.lensRadius;
    focalDistance_ = view.focalDistance;
  }
}

namespace {
// Shirley and Chiu's concentric map of the unit square onto the unit disk
// (pbrt's ConcentricSampleDisk): uniform, and nearby points stay near.
Vec2f concentricDisk(Vec2f u) {
  const float x = 2 * u.x - 1, y = 2 * u.y - 1;
  if (x == 0 && y == 0) return {0, 0};
  float r, theta;
  if (std::abs(x) > std::abs(y)) {
    r = x;
    theta = (kPi / 4) * (y / x);
  } else {
    r = y;
    theta = kPi / 2 - (kPi / 4) * (x / y);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}
}  // namespace

Vec3f Camera::lensPoint(Vec2f uLens) const {
  if (!hasLens()) return origin_;
  const Vec2f d = concentricDisk(uLens);
  return origin_ + right_ * (d.x * lensRadius_) + up_ * (d.y * lensRadius_);
}

void Camera::ray(float x, float y, Vec2f uLens, Vec3f& rayOrigin, Vec3f& rayDirection) const {
  if (!hasLens()) {
    rayOrigin = origin_;
    rayDirection = direction(x, y);
    return;
  }
  // The pinhole ray's point on the focal plane (the plane point's forward
  // component is 1).
  const Vec3f focus = origin_ + planePoint(x, y) * focalDistance_;
  rayOrigin = lensPoint(uLens);
  rayDirection = normalize(focus - rayOrigin);
}

bool Camera::project(Vec3f d, float& x, float& y) const {
  float z = dot(d, forward_);
  if (z <= 0) return false;
  // direction()'s plane position, inverted.
  x = (dot(d, right_) / z + tanHalfX_) / xScale_;
  y = (tanHalfY_ - dot(d, up_) / z) / yScale_;
  return true;
}

bool Camera::pixelOf(Vec3f point, uint32_t& pixel) const {
  return pixelOf(point, origin_, pixel);
}

bool Camera::pixelOf(Vec3f point, Vec3f lens, uint32_t& pixel) const {
  float x, y;
  Vec3f seen = point - origin_;
  if (hasLens()) {
    // Where the ray from the lens point through `point` meets the focal
    // plane, seen from the pinhole.
    const Vec3f w = point - lens;
    const float z = dot(w, forward_);
    if (!(z > 0)) return false;
    seen = lens + w * (focalDistance_ / z) - origin_;
  }
  if (!project(seen, x, y)) return false;
  x -= float(x0_);
  y -= float(y0_);
  if (!(x >= 0 && y >= 0 && x < float(width_) && y < float(height_))) return false;
  const uint32_t px = std::min(uint32_t(x), uint32_t(width_ - 1));
  const uint32_t py = std::min(uint32_t(y), uint32_t(height_ - 1));
  pixel = py * uint32_t(width_) + px;
  return true;
}

}  // namespace ferry
