// A rank's partial frame buffer: the sum of every contribution this rank
// computed, for any pixel. The distributed layer sums the ranks' buffers by
// direct send; on one rank it is the image.
//
// Sums are kept in fixed point (64-bit integers, kFractionBits below the
// binary point): integer addition is associative, so a pixel's sum does not
// depend on the order its contributions arrive in, and the ranks' partial
// sums add up to exactly the one-rank image at any rank count
// (docs/architecture.md, "Fixed-point frame buffer"). Adds are plain, for
// one thread per pixel at a time, unless setAtomicAdds(true) (light paths
// add to any pixel from any thread; docs/path-tracer.md, "Light paths").
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <vector>

#include "core/math.h"
#include "render/aov.h"

namespace ferry {

// pbrt's film clamp of one camera sample's radiance: v3's
// "maxsampleluminance" scales a sample whose luminance exceeds the limit
// down to it, v4's "maxcomponentvalue" one whose largest channel does.
struct SampleClamp {
  enum class Measure { None, Luminance, MaxComponent } measure = Measure::None;
  float limit = 0;
  bool active() const { return measure != Measure::None; }
  // The factor a sample of radiance `v` is scaled by (1: within the limit).
  float scale(Vec3f v) const;
};

class FrameBuffer {
 public:
  // 2^-28 (3.7e-9) resolution. A contribution is clamped to [0, 2^26]
  // (6.7e7); a pixel's sum may reach 2^35 (3.4e10) before the 64-bit total
  // could overflow, far above any radiance times sample count Ferry renders.
  static constexpr int kFractionBits = 28;
  static constexpr float kMaxContribution = float(1 << 26);

  FrameBuffer(int width, int height)
      : width_(width), height_(height), sum_(size_t(width) * height * 3, 0) {}

  // Adds one contribution of the pixel's camera sample. NaN and negative
  // values add nothing.
  void add(uint32_t pixel, Vec3f value) {
    addTo(clamp_.active() ? sampleSum_ : sum_, pixel, value);
  }
  // Adds a light path's contribution (a splat): under a sample clamp it is
  // clamped alone, as pbrt clamps light tracing's splats.
  void addSplat(uint32_t pixel, Vec3f value) {
    if (clamp_.active()) value = value * clamp_.scale(value);
    addTo(sum_, pixel, value);
  }

  // While `clamp` is active, add() collects the current camera sample of
  // every pixel apart; finishSample() then clamps each pixel's sample total
  // and adds it (if `addHere`: a distributed render sums the ranks' sample
  // totals first, sampleSums(), and one rank adds them). The totals are
  // integer sums, so the clamp does not depend on the order or the ranks.
  void setSampleClamp(const SampleClamp& clamp);
  const SampleClamp& sampleClamp() const { return clamp_; }
  std::vector<int64_t>& sampleSums() { return sampleSum_; }
  void finishSample(bool addHere);

 private:
  void addTo(std::vector<int64_t>& sums, uint32_t pixel, Vec3f value) {
    int64_t* s = &sums[size_t(pixel) * 3];
    if (atomicAdds_) {
      std::atomic_ref<int64_t>(s[0]).fetch_add(toFixed(value.x), std::memory_order_relaxed);
      std::atomic_ref<int64_t>(s[1]).fetch_add(toFixed(value.y), std::memory_order_relaxed);
      std::atomic_ref<int64_t>(s[2]).fetch_add(toFixed(value.z), std::memory_order_relaxed);
    } else {
      s[0] += toFixed(value.x);
      s[1] += toFixed(value.y);
      s[2] += toFixed(value.z);
    }
  }

 public:
  // Whether add() may be called for one pixel from several threads at once.
  void setAtomicAdds(bool atomic) { atomicAdds_ = atomic; }
  static int64_t toFixed(float v) {
    if (!(v > 0)) return 0;  // also NaN
    if (v > kMaxContribution) v = kMaxContribution;
    return int64_t(double(v) * double(int64_t(1) << kFractionBits) + 0.5);
  }
  static float toLinear(int64_t fixed, double scale) {
    return float(double(fixed) * (scale / double(int64_t(1) << kFractionBits)));
  }

  int width() const { return width_; }
  int height() const { return height_; }
  size_t pixelCount() const { return sum_.size() / 3; }
  // Three fixed-point channels per pixel, pixel after pixel.
  const std::vector<int64_t>& fixedSum() const { return sum_; }
  std::vector<int64_t>& fixedSum() { return sum_; }
  // The sums as floats (times `scale`).
  std::vector<Vec3f> sum(double scale = 1) const;
  void clear() {
    std::fill(sum_.begin(), sum_.end(), 0);
    std::fill(aovSum_.begin(), aovSum_.end(), 0);
  }

  // AOVs (render/aov.h). While `aovs` is not empty, addAovs() sums each
  // camera sample's first-surface values per pixel: aovChannels() a pixel,
  // pixel after pixel, in signed fixed point with the colour's resolution
  // (exact sums in any order and over any ranks, as the colour's). Setting
  // the same list again keeps the sums; another list starts them at zero.
  void setAovs(const std::vector<Aov>& aovs);
  const std::vector<Aov>& aovs() const { return aovs_; }
  bool hasAovs() const { return !aovs_.empty(); }
  int aovChannels() const { return aovChannels_; }
  // One camera sample's values (not clamped by a SampleClamp); for one
  // thread per pixel at a time.
  void addAovs(uint32_t pixel, const SurfaceAovs& values);
  const std::vector<int64_t>& fixedAovSum() const { return aovSum_; }
  std::vector<int64_t>& fixedAovSum() { return aovSum_; }
  // A signed value in fixed point: clamped to [-kMaxContribution,
  // kMaxContribution]; NaN is 0.
  static int64_t toFixedSigned(float v) {
    if (!(v == v)) return 0;
    v = std::clamp(v, -kMaxContribution, kMaxContribution);
    const double scaled = double(v) * double(int64_t(1) << kFractionBits);
    return int64_t(scaled < 0 ? scaled - 0.5 : scaled + 0.5);
  }

 private:
  int width_, height_;
  std::vector<int64_t> sum_;
  bool atomicAdds_ = false;
  SampleClamp clamp_;
  std::vector<int64_t> sampleSum_;  // the current camera sample, while clamped
  std::vector<Aov> aovs_;
  int aovChannels_ = 0;
  std::vector<int64_t> aovSum_;  // aovChannels_ a pixel
};

// Exposure (in stops), the ACES filmic curve (Narkowicz's fit), then sRGB.
struct ToneMapping {
  float exposure = 0;
  bool filmic = true;
  // The picture shows this AOV of the frame buffer instead of the colour
  // (an Aov's value; render/aov.h, aovPicture); -1, or one the buffer does
  // not have: the colour.
  int32_t aov = -1;
};
uint8_t toneMapChannel(float linear, const ToneMapping& toneMapping);
std::vector<uint8_t> toneMapToRgba8(const std::vector<Vec3f>& linear,
                                    const ToneMapping& toneMapping);

}  // namespace ferry
