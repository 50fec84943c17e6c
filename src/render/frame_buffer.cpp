#include "render/frame_buffer.h"

#include <cmath>

#include "scene/texture.h"

namespace ferry {

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
