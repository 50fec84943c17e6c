// Piecewise-constant distributions for importance sampling (environment
// images, emissive triangles by power).
#pragma once

#include <vector>

#include "core/math.h"

namespace ferry {

class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(std::vector<float> weights);
  // Continuous sample in [0, 1); pdf is the density over [0, 1).
  float sampleContinuous(float u, float& pdf, int& index) const;
  int sampleDiscrete(float u, float& probability) const;
  float discreteProbability(int index) const;
  float integral() const { return integral_; }
  int size() const { return int(weights_.size()); }

 private:
  std::vector<float> weights_;
  std::vector<float> cdf_;  // size + 1
  float integral_ = 0;
};

// Rows are the marginal, columns within a row the conditional.
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(const std::vector<float>& weights, int width, int height);
  Vec2f sample(Vec2f u, float& pdf) const;  // pdf over the unit square
  float pdf(Vec2f uv) const;
  bool empty() const { return rows_.empty(); }

 private:
  std::vector<Distribution1D> rows_;
  Distribution1D marginal_;
  int width_ = 0, height_ = 0;
};

}  // namespace ferry
