// Checked reading of the values a glTF material carries in its extensions
// (KHR_materials_*, and KHR_texture_transform on its texture references):
// each value has the type and the range its extension's schema gives, or the
// load fails with an InputError naming the file, the material, the
// extension and the value.
//
// The loader hands these functions the extensions' original JSON (tinygltf
// keeps it on request) rather than tinygltf's Value tree, which silently
// drops an extension that is not an object, a null value or an empty array,
// and wraps integers to int: each of those is a wrong value to report.
#pragma once

#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "core/math.h"
#include "io/gltf/gltf_texture_ref.h"

namespace ferry {

class GltfMaterialValues {
 public:
  // `where` opens every message (`scene.gltf: material "paint"`);
  // `textureCount`: how many textures the file has (references are checked).
  GltfMaterialValues(std::string where, size_t textureCount);

  // An `extensions` object kept as JSON text by tinygltf ("" when absent);
  // `owner` names where it is (`material`, `normalTexture`) in messages.
  nlohmann::json parseExtensions(const std::string& json, const std::string& owner) const;
  // Extension `name` of `extensions`, or null when absent; not an object: an error.
  const nlohmann::json* extension(const nlohmann::json& extensions, const std::string& name) const;

  // `object[key]`: a number in [min, max], finite as a float; `fallback` when
  // absent. `what` names the object in messages (the extension's name).
  float number(const nlohmann::json& object, const std::string& what, const char* key,
               float fallback, float min = -std::numeric_limits<float>::max(),
               float max = std::numeric_limits<float>::max()) const;
  // `object[key]`: an array of three numbers, each in [min, max].
  Vec3f color(const nlohmann::json& object, const std::string& what, const char* key,
              Vec3f fallback, float min, float max) const;
  // `object[key]`: a textureInfo (index, texCoord, KHR_texture_transform);
  // absent: no texture.
  GltfTextureRef texture(const nlohmann::json& object, const std::string& what,
                         const char* key) const;
  // A textureInfo of the core material as tinygltf read it, with the JSON
  // of its extensions (KHR_texture_transform is read from it).
  GltfTextureRef texture(int index, int texCoord, const std::string& extensionsJson,
                         const std::string& what) const;

  [[noreturn]] void fail(const std::string& message) const;

 private:
  int integer(const nlohmann::json& value, const std::string& what, int min) const;
  Vec2f pair(const nlohmann::json& object, const std::string& what, const char* key,
             Vec2f fallback) const;
  GltfTextureRef checkedReference(int index, int texCoord, const nlohmann::json* extensions,
                                  const std::string& what) const;

  std::string where_;
  size_t textureCount_;
};

}  // namespace ferry
