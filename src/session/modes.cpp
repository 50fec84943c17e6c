#include "session/modes.h"

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

PathLayout parsePathLayout(const std::string& name) {
  if (name == "auto") return PathLayout::Auto;
  if (name == "mask") return PathLayout::Mask;
  if (name == "replay") return PathLayout::Replay;
  throw InputError(fmt::format("path-layout '{}': expected auto, mask or replay", name));
}

std::string toString(PathLayout layout) {
  switch (layout) {
    case PathLayout::Auto:
      return "auto";
    case PathLayout::Mask:
      return "mask";
    case PathLayout::Replay:
      return "replay";
  }
  FERRY_CHECK(false);
  return {};
}

Retrace parseRetrace(const std::string& name) {
  if (name == "remote") return Retrace::Remote;
  if (name == "all") return Retrace::All;
  throw InputError(fmt::format("retrace '{}': expected remote or all", name));
}

std::string toString(Retrace retrace) {
  switch (retrace) {
    case Retrace::Remote:
      return "remote";
    case Retrace::All:
      return "all";
  }
  FERRY_CHECK(false);
  return {};
}

Instancing parseInstancing(const std::string& name) {
  if (name == "shared") return Instancing::Shared;
  if (name == "always") return Instancing::Always;
  throw InputError(fmt::format("instancing '{}': expected shared or always", name));
}

std::string toString(Instancing instancing) {
  switch (instancing) {
    case Instancing::Shared:
      return "shared";
    case Instancing::Always:
      return "always";
  }
  FERRY_CHECK(false);
  return {};
}

}  // namespace ferry
