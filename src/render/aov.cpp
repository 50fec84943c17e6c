#include "render/aov.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"
#include "render/frame_buffer.h"

namespace ferry {
namespace {

std::string knownNames() {
  std::string names;
  for (const AovSpec& spec : kAovSpecs)
    names += fmt::format("{}{}", names.empty() ? "" : ", ", spec.name);
  return names;
}

}  // namespace

std::vector<Aov> parseAovList(const std::string& text) {
  std::vector<Aov> aovs;
  size_t start = 0;
  while (start <= text.size() && !text.empty()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    const std::string name = text.substr(start, comma - start);
    Aov aov;
    if (!aovNamed(name, aov))
      throw InputError(
          fmt::format("unknown AOV '{}' in '{}' (known: {})", name, text, knownNames()));
    if (std::find(aovs.begin(), aovs.end(), aov) != aovs.end())
      throw InputError(fmt::format("AOV '{}' named twice in '{}'", name, text));
    aovs.push_back(aov);
    start = comma + 1;
  }
  return aovs;
}

std::string aovListText(const std::vector<Aov>& aovs) {
  std::string text;
  for (Aov aov : aovs) text += fmt::format("{}{}", text.empty() ? "" : ",", aovSpec(aov).name);
  return text;
}

int aovChannelCount(const std::vector<Aov>& aovs) {
  int channels = 0;
  for (Aov aov : aovs) channels += aovSpec(aov).channels;
  return channels;
}

bool aovNamed(const std::string& name, Aov& out) {
  for (const AovSpec& s : kAovSpecs)
    if (name == s.name) {
      out = s.aov;
      return true;
    }
  return false;
}

std::vector<uint8_t> aovPicture(const std::vector<float>& values, const std::vector<Aov>& aovs,
                                Aov shown, size_t pixels) {
  const int stride = aovChannelCount(aovs);
  int offset = 0;
  for (Aov a : aovs) {
    if (a == shown) break;
    offset += aovSpec(a).channels;
  }
  const int channels = aovSpec(shown).channels;
  std::vector<uint8_t> rgba(pixels * 4, 255);
  if (values.size() < pixels * size_t(stride)) return rgba;
  auto at = [&](size_t pixel, int c) {
    return values[pixel * size_t(stride) + size_t(offset + c)];
  };
  // Depth and position: each channel's range over the pixels the AOV saw.
  float lo[3] = {kInfinity, kInfinity, kInfinity}, hi[3] = {-kInfinity, -kInfinity, -kInfinity};
  for (size_t p = 0; p < pixels; ++p)
    for (int c = 0; c < channels; ++c) {
      const float v = at(p, c);
      if (!std::isfinite(v) || (shown == Aov::Depth && !(v > 0))) continue;
      lo[c] = std::min(lo[c], v);
      hi[c] = std::max(hi[c], v);
    }
  const ToneMapping srgb{0, false};
  for (size_t p = 0; p < pixels; ++p)
    for (int c = 0; c < 3; ++c) {
      const int k = shown == Aov::Depth ? 0 : c;
      const float v = k < channels ? at(p, k) : 0.0f;
      uint8_t byte = 0;
      switch (shown) {
        case Aov::Albedo:
        case Aov::Uv:
          byte = toneMapChannel(v, srgb);
          break;
        case Aov::Normal:
        case Aov::GeometricNormal:
          byte = uint8_t(std::lround(std::clamp(0.5f + 0.5f * v, 0.0f, 1.0f) * 255));
          break;
        case Aov::Depth:
        case Aov::Position: {
          const float range = hi[k] - lo[k];
          float t = range > 0 ? (v - lo[k]) / range : 0.0f;
          if (shown == Aov::Depth) t = v > 0 ? 1 - t : 0.0f;
          byte = uint8_t(std::lround(std::clamp(t, 0.0f, 1.0f) * 255));
          break;
        }
      }
      rgba[p * 4 + size_t(c)] = byte;
    }
  return rgba;
}

}  // namespace ferry
