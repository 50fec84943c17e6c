#include "builtin/builtin.h"

#include <charconv>
#include <cmath>
#include <set>
#include <string_view>

#include <fmt/format.h>

#include "builtin/cornell.h"
#include "builtin/fur.h"
#include "builtin/furnace.h"
#include "builtin/island.h"
#include "builtin/landscape.h"
#include "builtin/particles.h"
#include "builtin/scene_plan.h"
#include "builtin/tets.h"
#include "builtin/volume.h"
#include "core/error.h"

namespace ferry {
namespace {

constexpr std::string_view kPrefix = "builtin:";
constexpr const char* kAcceptedKeys =
    "scale (a positive number), seed (an integer 0..4294967295), size (builtin:volume: samples a "
    "side), strands (builtin:fur: hair strands), count (builtin:particles: spheres; builtin:tets: "
    "tetrahedra)";

struct BuiltinEntry {
  const char* name;
  builtin::ScenePlan (*plan)(const BuiltinParams& params);
  bool hasSize = false;     // takes `size` (and not `scale`)
  bool hasStrands = false;  // takes `strands` (and not `scale`)
  bool hasCount = false;    // takes `count` (and not `scale`)
};

// The order is the order `builtinNames()` lists them in.
constexpr BuiltinEntry kBuiltins[] = {
    {"island", [](const BuiltinParams& p) { return builtin::planIsland(p.scale, p.seed); }},
    {"landscape", [](const BuiltinParams& p) { return builtin::planLandscape(p.scale, p.seed); }},
    {"cornell", [](const BuiltinParams& p) { return builtin::planCornell(p.scale, p.seed); }},
    {"furnace", [](const BuiltinParams& p) { return builtin::planFurnace(p.scale, p.seed); }},
    {"volume",
     [](const BuiltinParams& p) {
       return builtin::planVolume(p.size.value_or(builtin::kDefaultVolumeSize), p.seed);
     },
     true},
    {"fur",
     [](const BuiltinParams& p) {
       return builtin::planFur(p.strands.value_or(builtin::kDefaultFurStrands), p.seed);
     },
     false, true},
    {"particles",
     [](const BuiltinParams& p) {
       return builtin::planParticles(p.count.value_or(builtin::kDefaultParticles), p.seed);
     },
     false, false, true},
    {"tets",
     [](const BuiltinParams& p) {
       return builtin::planTets(p.count.value_or(builtin::kDefaultTets), p.seed);
     },
     false, false, true},
};

std::string namesList() {
  std::string out;
  for (const BuiltinEntry& e : kBuiltins) out += (out.empty() ? "" : ", ") + std::string(e.name);
  return out;
}

const BuiltinEntry& lookup(const std::string& name, const std::string& spec) {
  for (const BuiltinEntry& e : kBuiltins)
    if (name == e.name) return e;
  throw InputError(
      fmt::format("unknown built-in scene '{}' in '{}' (built-ins: {})", name, spec, namesList()));
}

void checkScale(double scale, const std::string& what) {
  if (!std::isfinite(scale) || scale <= 0)
    throw InputError(fmt::format("{}: scale must be a positive number, got {}", what, scale));
}

builtin::ScenePlan planFor(const BuiltinParams& params) {
  std::string what = "builtin:" + params.name;
  const BuiltinEntry& entry = lookup(params.name, what);
  checkScale(params.scale, what);
  if (params.size && !entry.hasSize)
    throw InputError(fmt::format("{} has no size (builtin:volume has; use scale)", what));
  if (params.strands && !entry.hasStrands)
    throw InputError(fmt::format("{} has no strands (builtin:fur has)", what));
  if (params.count && !entry.hasCount)
    throw InputError(
        fmt::format("{} has no count (builtin:particles and builtin:tets have)", what));
  return entry.plan(params);
}

double parseScale(std::string_view text, const std::string& spec) {
  double value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value) || value <= 0)
    throw InputError(fmt::format(
        "bad scale '{}' in '{}': expected a positive number such as 0.5 or 4", text, spec));
  return value;
}

uint32_t parseSeed(std::string_view text, const std::string& spec) {
  uint32_t value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end)
    throw InputError(
        fmt::format("bad seed '{}' in '{}': expected an integer 0..4294967295", text, spec));
  return value;
}

}  // namespace

bool isBuiltinSpec(const std::string& spec) {
  return std::string_view(spec).starts_with(kPrefix);
}

BuiltinParams parseBuiltinSpec(const std::string& spec) {
  if (!isBuiltinSpec(spec))
    throw InputError(
        fmt::format("'{}' is not a built-in scene (expected builtin:NAME[?scale=S&seed=N], "
                    "built-ins: {})",
                    spec, namesList()));
  std::string_view rest = std::string_view(spec).substr(kPrefix.size());
  size_t question = rest.find('?');
  BuiltinParams params;
  params.name = std::string(rest.substr(0, question));
  lookup(params.name, spec);
  if (question == std::string_view::npos) return params;

  std::string_view query = rest.substr(question + 1);
  std::set<std::string, std::less<>> seen;
  while (!query.empty()) {
    size_t amp = query.find('&');
    std::string_view item = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    if (item.empty()) continue;  // tolerate "?&" and a trailing '&'
    size_t eq = item.find('=');
    if (eq == std::string_view::npos)
      throw InputError(fmt::format("parameter '{}' in '{}' needs a value (key=value; accepted: {})",
                                   item, spec, kAcceptedKeys));
    std::string_view key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "scale") {
      params.scale = parseScale(value, spec);
    } else if (key == "seed") {
      params.seed = parseSeed(value, spec);
    } else if (key == "size") {
      uint32_t size = 0;
      const char* end = value.data() + value.size();
      auto [ptr, ec] = std::from_chars(value.data(), end, size);
      if (value.empty() || ec != std::errc() || ptr != end || size < 2 || size > 4096)
        throw InputError(
            fmt::format("bad size '{}' in '{}': expected an integer 2..4096", value, spec));
      params.size = int(size);
    } else if (key == "strands" || key == "count") {
      uint64_t number = 0;
      const char* end = value.data() + value.size();
      auto [ptr, ec] = std::from_chars(value.data(), end, number);
      const uint64_t most = key == "strands" ? 100'000'000 : 1'000'000'000;
      if (value.empty() || ec != std::errc() || ptr != end || number < 1 || number > most)
        throw InputError(
            fmt::format("bad {} '{}' in '{}': expected an integer 1..{}", key, value, spec, most));
      (key == "strands" ? params.strands : params.count) = number;
    } else {
      throw InputError(
          fmt::format("unknown parameter '{}' in '{}' (accepted: {})", key, spec, kAcceptedKeys));
    }
    if (!seen.insert(std::string(key)).second)
      throw InputError(fmt::format("parameter '{}' given twice in '{}'", key, spec));
  }
  return params;
}

std::vector<std::string> builtinNames() {
  std::vector<std::string> names;
  for (const BuiltinEntry& e : kBuiltins) names.emplace_back(e.name);
  return names;
}

Scene generateBuiltin(const BuiltinParams& params, std::shared_ptr<MeshStore> store) {
  return builtin::materializePlan(planFor(params), std::move(store));
}

SceneSummary describeBuiltin(const BuiltinParams& params) {
  return builtin::describePlan(planFor(params));
}

}  // namespace ferry
