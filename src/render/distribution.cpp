#include "render/distribution.h"

#include <algorithm>

namespace ferry {

Distribution1D::Distribution1D(std::vector<float> weights) : weights_(std::move(weights)) {
  size_t n = weights_.size();
  cdf_.assign(n + 1, 0);
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    sum += std::max(0.0f, weights_[i]);
    cdf_[i + 1] = float(sum);
  }
  integral_ = float(sum / std::max<size_t>(n, 1));
  if (sum <= 0) {  // all zero: fall back to uniform so sampling stays defined
    for (size_t i = 0; i <= n; ++i) cdf_[i] = float(i) / float(n);
    for (float& w : weights_) w = 1;
  } else {
    for (size_t i = 1; i <= n; ++i) cdf_[i] = float(cdf_[i] / sum);
  }
  if (n) cdf_[n] = 1;
}

static int findInterval(const std::vector<float>& cdf, float u) {
  auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
  int i = int(it - cdf.begin()) - 1;
  return std::clamp(i, 0, int(cdf.size()) - 2);
}

float Distribution1D::sampleContinuous(float u, float& pdf, int& index) const {
  int n = size();
  index = findInterval(cdf_, u);
  float width = cdf_[index + 1] - cdf_[index];
  float du = width > 0 ? (u - cdf_[index]) / width : 0.5f;
  pdf = width * n;
  return std::min((index + du) / n, 0.99999994f);
}

int Distribution1D::sampleDiscrete(float u, float& probability) const {
  int index = findInterval(cdf_, u);
  probability = cdf_[index + 1] - cdf_[index];
  return index;
}

float Distribution1D::discreteProbability(int index) const {
  return cdf_[index + 1] - cdf_[index];
}

Distribution2D::Distribution2D(const std::vector<float>& weights, int width, int height)
    : width_(width), height_(height) {
  std::vector<float> rowIntegrals(height);
  rows_.reserve(height);
  for (int y = 0; y < height; ++y) {
    rows_.emplace_back(std::vector<float>(weights.begin() + size_t(y) * width,
                                          weights.begin() + size_t(y + 1) * width));
    rowIntegrals[y] = rows_.back().integral();
  }
  marginal_ = Distribution1D(rowIntegrals);
}

Vec2f Distribution2D::sample(Vec2f u, float& pdf) const {
  float pdfRow, pdfColumn;
  int row, column;
  float v = marginal_.sampleContinuous(u.y, pdfRow, row);
  float x = rows_[row].sampleContinuous(u.x, pdfColumn, column);
  pdf = pdfRow * pdfColumn;
  return {x, v};
}

float Distribution2D::pdf(Vec2f uv) const {
  int row = std::clamp(int(uv.y * height_), 0, height_ - 1);
  int column = std::clamp(int(uv.x * width_), 0, width_ - 1);
  return marginal_.discreteProbability(row) * height_ * rows_[row].discreteProbability(column) *
         width_;
}

}  // namespace ferry
