#include "render/aov.h"

#include <algorithm>

#include <fmt/format.h>

#include "core/error.h"

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
    const auto spec = std::find_if(kAovSpecs.begin(), kAovSpecs.end(),
                                   [&](const AovSpec& s) { return name == s.name; });
    if (spec == kAovSpecs.end())
      throw InputError(
          fmt::format("unknown AOV '{}' in '{}' (known: {})", name, text, knownNames()));
    if (std::find(aovs.begin(), aovs.end(), spec->aov) != aovs.end())
      throw InputError(fmt::format("AOV '{}' named twice in '{}'", name, text));
    aovs.push_back(spec->aov);
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

}  // namespace ferry
