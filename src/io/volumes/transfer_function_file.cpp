#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "io/json_numbers.h"
#include "io/text_file.h"
#include "io/volumes/volume_files.h"

namespace ferry {

TransferFunction readTransferFunction(const std::string& path) {
  const std::string text = readTextFile(path, "the transfer function");
  auto fail = [&](const std::string& what) {
    throw InputError(
        fmt::format("{}: {} (expected {{\"colors\": [[x, r, g, b], ...], "
                    "\"opacity\": [[x, a], ...], \"scale\": S}})",
                    path, what));
  };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    fail(fmt::format("not JSON: {}", e.what()));
  }
  if (!j.is_object()) fail("not a JSON object");
  std::vector<TransferFunction::ColorPoint> colors;
  std::vector<TransferFunction::OpacityPoint> opacities;
  auto numbers = [&](const nlohmann::json& row, size_t n, const char* what, size_t index) {
    if (!row.is_array() || row.size() != n)
      fail(fmt::format("\"{}\" entry {} is not {} numbers", what, index, n));
    std::vector<float> out;
    for (const auto& v : row) {
      const std::optional<float> f = numberAs<float>(v);
      if (!f) fail(fmt::format("\"{}\" entry {} is not {} numbers", what, index, n));
      out.push_back(*f);
    }
    return out;
  };
  if (!j.contains("colors") || !j["colors"].is_array()) fail("no \"colors\" list");
  if (!j.contains("opacity") || !j["opacity"].is_array()) fail("no \"opacity\" list");
  for (size_t i = 0; i < j["colors"].size(); ++i) {
    const auto v = numbers(j["colors"][i], 4, "colors", i);
    colors.push_back({v[0], {v[1], v[2], v[3]}});
  }
  for (size_t i = 0; i < j["opacity"].size(); ++i) {
    const auto v = numbers(j["opacity"][i], 2, "opacity", i);
    opacities.push_back({v[0], v[1]});
  }
  float scale = TransferFunction::standard().scale();
  if (j.contains("scale")) {
    const std::optional<float> f = numberAs<float>(j["scale"]);
    if (!f) fail("\"scale\" is not a finite number");
    scale = *f;
  }
  try {
    return TransferFunction(std::move(colors), std::move(opacities), scale);
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
  return TransferFunction::standard();  // (not reached)
}

}  // namespace ferry
