// A rank's partial frame buffer: the sum of every contribution this rank
// computed, for any pixel. The distributed layer sums the ranks' buffers by
// direct send; on one rank it is the image.
//
// Writes are not atomic: a wavefront touches each pixel at most once (one
// path and one shadow ray per pixel sample, and the path adds light only after
// a delta vertex, which spawns no shadow ray; Bsdf tests that a sample is
// delta exactly when its lobe is), which also makes the summation order, and
// so the image, independent of the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace ferry {

class FrameBuffer {
 public:
  FrameBuffer(int width, int height)
      : width_(width), height_(height), sum_(size_t(width) * height) {}
  void add(uint32_t pixel, Vec3f value) { sum_[pixel] += value; }
  int width() const { return width_; }
  int height() const { return height_; }
  size_t pixelCount() const { return sum_.size(); }
  const std::vector<Vec3f>& sum() const { return sum_; }
  std::vector<Vec3f>& sum() { return sum_; }

 private:
  int width_, height_;
  std::vector<Vec3f> sum_;
};

// Exposure (in stops), the ACES filmic curve (Narkowicz's fit), then sRGB.
struct ToneMapping {
  float exposure = 0;
  bool filmic = true;
};
uint8_t toneMapChannel(float linear, const ToneMapping& toneMapping);
std::vector<uint8_t> toneMapToRgba8(const std::vector<Vec3f>& linear,
                                    const ToneMapping& toneMapping);

}  // namespace ferry
