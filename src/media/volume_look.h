// How a volume drawn through a transfer function looks, changed by the user
// after loading: an opacity scale and a named colour map, as sci-vis tools
// offer them (ParaView's presets, matplotlib's perceptual maps), for every
// such volume of a scene (--volume-opacity, --color-map, the viewer).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "media/transfer_function.h"

namespace ferry {

// "cool-to-warm" (ParaView's default), "viridis", "inferno",
// "black-body" (ParaView's Black-Body Radiation), "grayscale", in that order.
const std::vector<std::string>& colorMapNames();
// The map's points over [0, 1]; nullopt for a name not in colorMapNames().
std::optional<std::vector<TransferFunction::ColorPoint>> colorMap(std::string_view name);

struct VolumeLook {
  float opacity = 1;     // times each volume's own opacity scale
  std::string colorMap;  // a colorMapNames() entry; empty: each volume's own colours
  bool isDefault() const { return opacity == 1 && colorMap.empty(); }
};

// `loaded` (a transfer function as its volume was loaded) with `look`.
// Throws std::invalid_argument for an unknown colour map or an opacity
// scale that is not positive and finite.
TransferFunction restyled(const TransferFunction& loaded, const VolumeLook& look);

}  // namespace ferry
