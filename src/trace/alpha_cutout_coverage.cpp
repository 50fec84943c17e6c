#include "trace/alpha_cutout_coverage.h"

#include <algorithm>

namespace ferry {
namespace {

// Rounding in the bilinear blend moves alpha by a few ulps of 1: a bound
// this far from the cutoff decides.
constexpr float kMargin = 1e-5f;

AlphaCoverage::Cell classify(uint8_t lo, uint8_t hi, float cutoff, AlphaTest test) {
  using Cell = AlphaCoverage::Cell;
  switch (test) {
    case AlphaTest::Below:
      if (hi / 255.0f < cutoff - kMargin) return Cell::Hole;
      if (lo / 255.0f >= cutoff + kMargin) return Cell::Solid;
      return Cell::Mixed;
    case AlphaTest::Zero:
      // Weights are non-negative and one product of them is at least 1/4:
      // all zero blends to exactly 0, all positive to above 0.
      if (hi == 0) return Cell::Hole;
      return lo > 0 ? Cell::Solid : Cell::Mixed;
    case AlphaTest::Stochastic:
      // Alpha 0 is a hole for every ray; 255s may blend to just below 1,
      // which some rays pass.
      return hi == 0 ? Cell::Hole : Cell::Mixed;
  }
  return Cell::Mixed;
}

}  // namespace

AlphaCoverage::AlphaCoverage(const Texture& texture, float cutoff, AlphaTest test)
    : width_(texture.width), height_(texture.height) {
  const size_t w = size_t(std::max(0, width_)), h = size_t(std::max(0, height_));
  bits_.assign((w * h + 3) / 4, 0);
  if (w == 0 || h == 0) return;
  // A footprint at (x0, y0) blends columns x0 and x1, x1 one of x0 - 1, x0,
  // x0 + 1 (wrapping around for repeat; mirror steps back at the far end),
  // and rows likewise: min and max over the 3 x 3 block, separably.
  std::vector<uint8_t> rowLo(w * h), rowHi(w * h);
  for (size_t y = 0; y < h; ++y)
    for (size_t x = 0; x < w; ++x) {
      const size_t left = (x + w - 1) % w, right = (x + 1) % w;
      const uint8_t* row = &texture.rgba[y * w * 4];
      const uint8_t a = row[left * 4 + 3], b = row[x * 4 + 3], c = row[right * 4 + 3];
      rowLo[y * w + x] = std::min({a, b, c});
      rowHi[y * w + x] = std::max({a, b, c});
    }
  for (size_t y = 0; y < h; ++y) {
    const size_t up = (y + h - 1) % h, down = (y + 1) % h;
    for (size_t x = 0; x < w; ++x) {
      const uint8_t lo = std::min({rowLo[up * w + x], rowLo[y * w + x], rowLo[down * w + x]});
      const uint8_t hi = std::max({rowHi[up * w + x], rowHi[y * w + x], rowHi[down * w + x]});
      const size_t i = y * w + x;
      bits_[i >> 2] |= uint8_t(uint8_t(classify(lo, hi, cutoff, test)) << ((i & 3) * 2));
    }
  }
}

double AlphaCoverage::decidedShare() const {
  const size_t n = size_t(width_) * size_t(height_);
  if (n == 0) return 0;
  size_t decided = 0;
  for (size_t i = 0; i < n; ++i) decided += cell(i) != Cell::Mixed;
  return double(decided) / double(n);
}

}  // namespace ferry
