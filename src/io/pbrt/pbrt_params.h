// The parameter lists of pbrt directives ("float fov" [ 45 ], "point3 P"
// [ ... ], "texture reflectance" "wood"): parsed and type-checked once, looked
// up by name, and remembered as used or not, so every parameter Ferry does
// not understand can be reported instead of silently dropped.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/math.h"

namespace ferry {

class PbrtTokenSource;

struct PbrtParam {
  // Canonical type: bool integer float point2 vector2 point3 vector3 normal rgb
  // spectrum blackbody string texture. v3's spellings map onto these: point
  // -> point3, vector -> vector3, normal3 -> normal, color -> rgb.
  std::string type;
  std::string name;
  std::vector<float> floats;  // float, point*, vector*, normal, rgb, blackbody, numeric spectrum
  std::vector<int32_t> ints;  // integer
  std::vector<std::string> strings;  // string, texture, named or file spectrum
  std::vector<uint8_t> bools;        // bool
  SourceLocation where;              // of its "type name" string
  mutable bool used = false;

  size_t size() const;  // number of values as written
  // "float fov" as written, for messages.
  std::string declaration() const { return type + " " + name; }
};

class PbrtParams {
 public:
  // Reads "type name" value pairs until the next token is not a string.
  // Errors (at the offending token): a malformed "type name", an unknown type,
  // a value of the wrong kind ("float" given a string, a non-finite or
  // unparsable number, an integer outside 32 bits), an empty or unclosed
  // list, a parameter given twice.
  static PbrtParams parse(PbrtTokenSource& tokens);

  void add(PbrtParam param);
  bool empty() const { return params_.empty(); }
  const std::vector<PbrtParam>& all() const { return params_; }

  // The parameter `name` of any type, marked used; nullptr if absent.
  const PbrtParam* find(std::string_view name) const;
  bool has(std::string_view name) const;

  // Typed single values; absent: `fallback`. Present with another type or
  // another number of values: InputError at the parameter.
  float getFloat(std::string_view name, float fallback) const;
  int32_t getInt(std::string_view name, int32_t fallback) const;
  bool getBool(std::string_view name, bool fallback) const;
  std::string getString(std::string_view name, const std::string& fallback) const;
  std::optional<Vec3f> getPoint3(std::string_view name) const;  // point3/vector3/normal, one value

  // Arrays; nullptr if absent. `types` lists accepted canonical types.
  const PbrtParam* getArray(std::string_view name,
                            std::initializer_list<std::string_view> types) const;

  // Parameters that were never looked up.
  std::vector<const PbrtParam*> unused() const;
  // Marks everything used (after a directive that is skipped as a whole).
  void markAllUsed() const;
  // Adds the parameters of `defaults` that this list does not have (v4's
  // `Attribute "shape" ...`).
  void addDefaults(const PbrtParams& defaults);

  [[noreturn]] static void fail(const PbrtParam& p, const std::string& message);

 private:
  std::vector<PbrtParam> params_;
};

// Parses a pbrt number word; nullopt if it is not one. Rejects nan and inf.
std::optional<double> parsePbrtNumber(std::string_view text);

}  // namespace ferry
