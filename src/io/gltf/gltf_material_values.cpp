#include "io/gltf/gltf_material_values.h"

#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {
namespace {

// A value as the file wrote it, for messages (long arrays or objects cut).
std::string shown(const nlohmann::json& value) {
  std::string s = value.dump();
  return s.size() <= 40 ? s : s.substr(0, 37) + "...";
}

std::string rangeText(float min, float max) {
  if (max == std::numeric_limits<float>::max()) return fmt::format("at least {}", min);
  return fmt::format("in [{}, {}]", min, max);
}

}  // namespace

GltfMaterialValues::GltfMaterialValues(std::string where, size_t textureCount)
    : where_(std::move(where)), textureCount_(textureCount) {}

void GltfMaterialValues::fail(const std::string& message) const {
  throw InputError(fmt::format("{}: {}", where_, message));
}

nlohmann::json GltfMaterialValues::parseExtensions(const std::string& json,
                                                   const std::string& owner) const {
  if (json.empty()) return nlohmann::json::object();
  nlohmann::json parsed = nlohmann::json::parse(json, nullptr, false);
  if (parsed.is_discarded()) fail(fmt::format("{} extensions are not valid JSON", owner));
  if (!parsed.is_object())
    fail(fmt::format("{} extensions are {}, not an object", owner, shown(parsed)));
  return parsed;
}

const nlohmann::json* GltfMaterialValues::extension(const nlohmann::json& extensions,
                                                    const std::string& name) const {
  auto it = extensions.find(name);
  if (it == extensions.end()) return nullptr;
  if (!it->is_object()) fail(fmt::format("{} is {}, not an object", name, shown(*it)));
  return &*it;
}

float GltfMaterialValues::number(const nlohmann::json& object, const std::string& what,
                                 const char* key, float fallback, float min, float max) const {
  auto it = object.find(key);
  if (it == object.end()) return fallback;
  if (!it->is_number()) fail(fmt::format("{} {} is {}, not a number", what, key, shown(*it)));
  const double value = it->get<double>();
  if (!std::isfinite(float(value)))
    fail(fmt::format("{} {} is {}: not a finite single-precision number", what, key, shown(*it)));
  if (!(value >= min && value <= max))
    fail(fmt::format("{} {} is {}: must be {}", what, key, shown(*it), rangeText(min, max)));
  return float(value);
}

Vec3f GltfMaterialValues::color(const nlohmann::json& object, const std::string& what,
                                const char* key, Vec3f fallback, float min, float max) const {
  auto it = object.find(key);
  if (it == object.end()) return fallback;
  if (!it->is_array() || it->size() != 3)
    fail(fmt::format("{} {} is {}, not an array of 3 numbers", what, key, shown(*it)));
  Vec3f out;
  for (int c = 0; c < 3; ++c) {
    const nlohmann::json channel = nlohmann::json::object({{key, (*it)[size_t(c)]}});
    out[c] = number(channel, what, key, 0, min, max);
  }
  return out;
}

Vec2f GltfMaterialValues::pair(const nlohmann::json& object, const std::string& what,
                               const char* key, Vec2f fallback) const {
  auto it = object.find(key);
  if (it == object.end()) return fallback;
  if (!it->is_array() || it->size() != 2)
    fail(fmt::format("{} {} is {}, not an array of 2 numbers", what, key, shown(*it)));
  Vec2f out;
  for (int c = 0; c < 2; ++c) {
    const nlohmann::json element = nlohmann::json::object({{key, (*it)[size_t(c)]}});
    out[c] = number(element, what, key, 0);
  }
  return out;
}

int GltfMaterialValues::integer(const nlohmann::json& value, const std::string& what,
                                int min) const {
  // JSON has numbers, not integers: 2.0 is 2, 2.5 is not an index.
  if (!value.is_number() || value.get<double>() != std::floor(value.get<double>()))
    fail(fmt::format("{} is {}, not an integer", what, shown(value)));
  const double v = value.get<double>();
  if (v < min) fail(fmt::format("{} is {}: must be at least {}", what, shown(value), min));
  if (v > std::numeric_limits<int>::max())
    fail(fmt::format("{} is {}: too large", what, shown(value)));
  return int(v);
}

GltfTextureRef GltfMaterialValues::texture(const nlohmann::json& object, const std::string& what,
                                           const char* key) const {
  auto it = object.find(key);
  if (it == object.end()) return {};
  const std::string name = fmt::format("{} {}", what, key);
  if (!it->is_object()) fail(fmt::format("{} is {}, not a textureInfo object", name, shown(*it)));
  auto index = it->find("index");
  if (index == it->end()) fail(fmt::format("{} has no index", name));
  auto texCoord = it->find("texCoord");
  auto extensions = it->find("extensions");
  const nlohmann::json* extensionsObject = nullptr;
  if (extensions != it->end()) {
    if (!extensions->is_object())
      fail(fmt::format("{} extensions are {}, not an object", name, shown(*extensions)));
    extensionsObject = &*extensions;
  }
  return checkedReference(integer(*index, name + " index", 0),
                          texCoord == it->end() ? 0 : integer(*texCoord, name + " texCoord", 0),
                          extensionsObject, name);
}

GltfTextureRef GltfMaterialValues::texture(int index, int texCoord,
                                           const std::string& extensionsJson,
                                           const std::string& what) const {
  if (index < 0) return {};
  if (texCoord < 0) fail(fmt::format("{} texCoord is {}: must be at least 0", what, texCoord));
  const nlohmann::json extensions = parseExtensions(extensionsJson, what);
  return checkedReference(index, texCoord, &extensions, what);
}

GltfTextureRef GltfMaterialValues::checkedReference(int index, int texCoord,
                                                    const nlohmann::json* extensions,
                                                    const std::string& what) const {
  if (size_t(index) >= textureCount_)
    fail(fmt::format("{} uses texture {}, which does not exist ({} textures)", what, index,
                     textureCount_));
  GltfTextureRef ref;
  ref.index = index;
  ref.texCoord = texCoord;
  const nlohmann::json* transform =
      extensions ? extension(*extensions, "KHR_texture_transform") : nullptr;
  if (!transform) return ref;
  const std::string name = what + " KHR_texture_transform";
  ref.transform.offset = pair(*transform, name, "offset", {0, 0});
  ref.transform.rotation = number(*transform, name, "rotation", 0);
  ref.transform.scale = pair(*transform, name, "scale", {1, 1});
  auto set = transform->find("texCoord");
  if (set != transform->end()) ref.texCoord = integer(*set, name + " texCoord", 0);
  return ref;
}

}  // namespace ferry
