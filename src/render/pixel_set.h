// The pixels one sample renders here: every pixel of [first, last), or, when
// data groups split a sample, every stride-th band of `band` pixels of it,
// starting at band `phase`. Interleaved bands give each group a share of
// every part of the image (the sky and the ground alike), so the groups
// finish a split sample together.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

namespace ferry {

struct PixelSet {
  uint32_t first = 0, last = 0;
  uint32_t band = 1, stride = 1, phase = 0;

  static PixelSet range(uint32_t first, uint32_t last) { return {first, last, 1, 1, 0}; }
  // Bands of `band` pixels of [first, last) dealt in turn to `stride` takers;
  // taker `phase`'s share.
  static PixelSet interleaved(uint32_t first, uint32_t last, uint32_t band, uint32_t stride,
                              uint32_t phase) {
    return {first, last, std::max(band, 1u), std::max(stride, 1u), phase};
  }

  bool contains(uint32_t pixel) const {
    return pixel >= first && pixel < last && ((pixel - first) / band) % stride == phase;
  }
  // Calls f(begin, end) for each contiguous run of the set, in order.
  template <typename F>
  void forEachRun(F&& f) const {
    if (stride == 1) {
      if (first < last) f(first, last);
      return;
    }
    for (uint64_t begin = uint64_t(first) + uint64_t(phase) * band; begin < last;
         begin += uint64_t(stride) * band)
      f(uint32_t(begin), uint32_t(std::min<uint64_t>(begin + band, last)));
  }
  // `out` replaced by the set's pixels, in order.
  void list(std::vector<uint32_t>& out) const {
    out.clear();
    forEachRun([&](uint32_t b, uint32_t e) {
      for (uint32_t p = b; p != e; ++p) out.push_back(p);
    });
  }
  uint32_t size() const {
    uint32_t n = 0;
    forEachRun([&](uint32_t b, uint32_t e) { n += e - b; });
    return n;
  }
  bool operator==(const PixelSet&) const = default;
};

}  // namespace ferry
