// Named colour maps, as sci-vis tools offer them for a transfer function
// (ParaView's presets, matplotlib's perceptual maps): a viewer or a command
// line picks one by name for every volume drawn through a transfer function.
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

}  // namespace ferry
