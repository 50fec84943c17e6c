#include "media/volume_look.h"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace ferry {
namespace {

using Points = std::vector<TransferFunction::ColorPoint>;

// Each map at a few of its points, the values the tools publish (used as
// albedo, as the default map's are), interpolated linearly in between.
const std::vector<std::pair<std::string, Points>>& maps() {
  static const std::vector<std::pair<std::string, Points>> m = {
      {"cool-to-warm", TransferFunction::standard().colors()},
      {"viridis",
       {{0.000f, {0.267f, 0.005f, 0.329f}},
        {0.125f, {0.283f, 0.141f, 0.458f}},
        {0.250f, {0.230f, 0.322f, 0.546f}},
        {0.375f, {0.173f, 0.449f, 0.558f}},
        {0.500f, {0.128f, 0.567f, 0.551f}},
        {0.625f, {0.135f, 0.659f, 0.518f}},
        {0.750f, {0.267f, 0.749f, 0.441f}},
        {0.875f, {0.478f, 0.821f, 0.318f}},
        {1.000f, {0.993f, 0.906f, 0.144f}}}},
      {"inferno",
       {{0.000f, {0.001f, 0.000f, 0.014f}},
        {0.125f, {0.087f, 0.045f, 0.225f}},
        {0.250f, {0.258f, 0.039f, 0.406f}},
        {0.375f, {0.416f, 0.091f, 0.433f}},
        {0.500f, {0.578f, 0.148f, 0.404f}},
        {0.625f, {0.736f, 0.216f, 0.330f}},
        {0.750f, {0.865f, 0.317f, 0.226f}},
        {0.875f, {0.955f, 0.469f, 0.100f}},
        {1.000f, {0.988f, 0.998f, 0.645f}}}},
      {"black-body",
       {{0.0f, {0.0f, 0.0f, 0.0f}},
        {0.4f, {0.902f, 0.0f, 0.0f}},
        {0.8f, {0.902f, 0.902f, 0.0f}},
        {1.0f, {1.0f, 1.0f, 1.0f}}}},
      {"grayscale", {{0.0f, {0.0f, 0.0f, 0.0f}}, {1.0f, {1.0f, 1.0f, 1.0f}}}},
  };
  return m;
}

}  // namespace

const std::vector<std::string>& colorMapNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const auto& [name, points] : maps()) n.push_back(name);
    return n;
  }();
  return names;
}

std::optional<std::vector<TransferFunction::ColorPoint>> colorMap(std::string_view name) {
  for (const auto& [n, points] : maps())
    if (n == name) return points;
  return std::nullopt;
}

TransferFunction restyled(const TransferFunction& loaded, const VolumeLook& look) {
  if (!(look.opacity > 0) || !std::isfinite(look.opacity))
    throw std::invalid_argument("the volume opacity scale must be positive and finite");
  TransferFunction tf = loaded.withScale(loaded.scale() * look.opacity);
  if (look.colorMap.empty()) return tf;
  const auto colors = colorMap(look.colorMap);
  if (!colors) throw std::invalid_argument("no colour map named '" + look.colorMap + "'");
  return tf.withColors(*colors);
}

}  // namespace ferry
