#include "media/transfer_function.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace ferry {
namespace {

template <typename Point>
void checkPositions(const std::vector<Point>& points, const char* what) {
  if (points.empty()) throw std::invalid_argument(fmt::format("{}: no control points", what));
  for (size_t i = 0; i < points.size(); ++i) {
    if (!(points[i].x >= 0 && points[i].x <= 1))
      throw std::invalid_argument(
          fmt::format("{} point {}: position {} is outside [0, 1]", what, i, points[i].x));
    if (i > 0 && !(points[i].x > points[i - 1].x))
      throw std::invalid_argument(fmt::format("{} point {}: positions must increase ({} after {})",
                                              what, i, points[i].x, points[i - 1].x));
  }
}

// The piecewise-linear value of `points` at v (flat beyond the ends).
template <typename Point, typename Value>
auto interpolate(const std::vector<Point>& points, float v, Value Point::*value) {
  if (!(v > points.front().x)) return points.front().*value;
  if (!(v < points.back().x)) return points.back().*value;
  const auto upper = std::upper_bound(points.begin(), points.end(), v,
                                      [](float x, const Point& p) { return x < p.x; });
  const Point& b = *upper;
  const Point& a = *(upper - 1);
  const float t = (v - a.x) / (b.x - a.x);
  return a.*value * (1 - t) + b.*value * t;
}

}  // namespace

TransferFunction::TransferFunction(std::vector<ColorPoint> colors,
                                   std::vector<OpacityPoint> opacities, float scale)
    : colors_(std::move(colors)), opacities_(std::move(opacities)), scale_(scale) {
  checkPositions(colors_, "colour map");
  checkPositions(opacities_, "opacity ramp");
  for (size_t i = 0; i < colors_.size(); ++i) {
    const Vec3f c = colors_[i].rgb;
    if (!(std::min({c.x, c.y, c.z}) >= 0 && maxComponent(c) <= 1))
      throw std::invalid_argument(fmt::format(
          "colour map point {}: colour ({}, {}, {}) is outside [0, 1]", i, c.x, c.y, c.z));
  }
  for (size_t i = 0; i < opacities_.size(); ++i)
    if (!(opacities_[i].opacity >= 0) || !std::isfinite(opacities_[i].opacity))
      throw std::invalid_argument(fmt::format("opacity ramp point {}: opacity {} must be 0 or more",
                                              i, opacities_[i].opacity));
  if (!(scale_ >= 0) || !std::isfinite(scale_))
    throw std::invalid_argument(fmt::format("opacity scale {} must be 0 or more", scale_));
}

TransferFunction TransferFunction::standard() {
  // ParaView's "Cool to Warm" (Moreland 2009) at five of its points.
  return TransferFunction({{0.0f, {0.230f, 0.299f, 0.754f}},
                           {0.25f, {0.552f, 0.690f, 0.996f}},
                           {0.5f, {0.865f, 0.865f, 0.865f}},
                           {0.75f, {0.958f, 0.604f, 0.482f}},
                           {1.0f, {0.706f, 0.016f, 0.150f}}},
                          {{0.0f, 0.0f}, {1.0f, 1.0f}}, 20.0f);
}

Vec3f TransferFunction::color(float v) const {
  return interpolate(colors_, v, &ColorPoint::rgb);
}

float TransferFunction::opacity(float v) const {
  return interpolate(opacities_, v, &OpacityPoint::opacity);
}

TransferFunction TransferFunction::withScale(float scale) const {
  return TransferFunction(colors_, opacities_, scale);
}

TransferFunction TransferFunction::withColors(std::vector<ColorPoint> colors) const {
  return TransferFunction(std::move(colors), opacities_, scale_);
}

std::pair<float, float> TransferFunction::opacityRange(float lo, float hi) const {
  float smallest = std::min(opacity(lo), opacity(hi));
  float largest = std::max(opacity(lo), opacity(hi));
  for (const OpacityPoint& p : opacities_)
    if (p.x > lo && p.x < hi) {
      smallest = std::min(smallest, p.opacity);
      largest = std::max(largest, p.opacity);
    }
  return {smallest, largest};
}

}  // namespace ferry
