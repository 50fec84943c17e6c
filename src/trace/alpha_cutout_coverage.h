// What an image alpha test decides over each bilinear footprint, so that
// most tests of a cut-out (leaf cards, fences) read 2 bits instead of four
// texels: per footprint (named by its first tap, Texture::Taps' x0, y0) a
// hole wherever in it the hit falls, never a hole, or mixed (the exact test
// decides). A footprint is decided only where the exact test cannot answer
// otherwise: its possible neighbours in every wrap mode are counted, and the
// bounds keep a margin for rounding, so images do not change.
#pragma once

#include <cstdint>
#include <vector>

#include "scene/scene.h"

namespace ferry {

class AlphaCoverage {
 public:
  enum class Cell : uint8_t { Mixed = 0, Hole = 1, Solid = 2 };

  // For `texture` (with texels) tested as a material's alpha test does.
  AlphaCoverage(const Texture& texture, float cutoff, AlphaTest test);

  Cell at(int x, int y) const { return cell(size_t(y) * size_t(width_) + size_t(x)); }
  uint64_t bytes() const { return bits_.size(); }
  // Footprints decided without texels (Hole or Solid), of all.
  double decidedShare() const;

 private:
  Cell cell(size_t i) const { return Cell((bits_[i >> 2] >> ((i & 3) * 2)) & 3); }

  int width_ = 0, height_ = 0;
  std::vector<uint8_t> bits_;  // 2 bits per footprint, 4 to a byte
};

}  // namespace ferry
