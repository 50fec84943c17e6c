#include "render/frame_buffer.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "scene/texture.h"

namespace ferry {

float SampleClamp::scale(Vec3f v) const {
  float measured = 0;
  switch (measure) {
    case Measure::None:
      return 1;
    case Measure::Luminance:  // pbrt-v3's RGBSpectrum::y()
      measured = 0.212671f * v.x + 0.715160f * v.y + 0.072169f * v.z;
      break;
    case Measure::MaxComponent:
      measured = std::max({v.x, v.y, v.z});
      break;
  }
  return measured > limit ? limit / measured : 1.0f;
}

void FrameBuffer::setSampleClamp(const SampleClamp& clamp) {
  clamp_ = clamp;
  if (!clamp_.active())
    sampleSum_ = {};
  else if (sampleSum_.size() != sum_.size())
    sampleSum_.assign(sum_.size(), 0);
}

void FrameBuffer::finishSample(bool addHere) {
  if (!clamp_.active()) return;
  if (addHere) {
    for (size_t p = 0; p < pixelCount(); ++p) {
      const int64_t* s = &sampleSum_[3 * p];
      const Vec3f total(toLinear(s[0], 1), toLinear(s[1], 1), toLinear(s[2], 1));
      const float scale = clamp_.scale(total);
      int64_t* out = &sum_[3 * p];
      if (scale == 1) {
        for (int k = 0; k < 3; ++k) out[k] += s[k];
      } else {
        const Vec3f clamped = total * scale;
        out[0] += toFixed(clamped.x);
        out[1] += toFixed(clamped.y);
        out[2] += toFixed(clamped.z);
      }
    }
  }
  std::fill(sampleSum_.begin(), sampleSum_.end(), 0);
}

void FrameBuffer::setAovs(const std::vector<Aov>& aovs) {
  const int channels = aovChannelCount(aovs);
  const size_t size = pixelCount() * size_t(channels);
  if (aovs == aovs_ && aovSum_.size() == size) return;
  aovs_ = aovs;
  aovChannels_ = channels;
  aovSum_.assign(size, 0);
}

void FrameBuffer::addAovs(uint32_t pixel, const SurfaceAovs& values) {
  int64_t* s = &aovSum_[size_t(pixel) * size_t(aovChannels_)];
  auto add = [&s](std::initializer_list<float> v) {
    for (float x : v) *s++ += toFixedSigned(x);
  };
  for (Aov aov : aovs_) {
    switch (aov) {
      case Aov::Albedo:
        add({values.albedo.x, values.albedo.y, values.albedo.z});
        break;
      case Aov::Normal:
        add({values.shadingNormal.x, values.shadingNormal.y, values.shadingNormal.z});
        break;
      case Aov::GeometricNormal:
        add({values.geometricNormal.x, values.geometricNormal.y, values.geometricNormal.z});
        break;
      case Aov::Depth:
        add({values.depth});
        break;
      case Aov::Position:
        add({values.position.x, values.position.y, values.position.z});
        break;
      case Aov::Uv:
        add({values.uv.x, values.uv.y});
        break;
    }
  }
}

std::vector<Vec3f> FrameBuffer::sum(double scale) const {
  std::vector<Vec3f> out(pixelCount());
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = Vec3f(toLinear(sum_[3 * i], scale), toLinear(sum_[3 * i + 1], scale),
                   toLinear(sum_[3 * i + 2], scale));
  return out;
}

uint8_t toneMapChannel(float x, const ToneMapping& tm) {
  if (!std::isfinite(x)) x = 0;
  x = std::max(0.0f, x) * std::exp2(tm.exposure);
  if (tm.filmic)
    x = std::clamp((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f), 0.0f, 1.0f);
  return static_cast<uint8_t>(std::lround(linearToSrgb(x) * 255.0f));
}

std::vector<uint8_t> toneMapToRgba8(const std::vector<Vec3f>& linear, const ToneMapping& tm) {
  std::vector<uint8_t> out(linear.size() * 4);
  for (size_t i = 0; i < linear.size(); ++i) {
    out[4 * i + 0] = toneMapChannel(linear[i].x, tm);
    out[4 * i + 1] = toneMapChannel(linear[i].y, tm);
    out[4 * i + 2] = toneMapChannel(linear[i].z, tm);
    out[4 * i + 3] = 255;
  }
  return out;
}

}  // namespace ferry
