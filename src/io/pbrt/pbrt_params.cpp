#include "io/pbrt/pbrt_params.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "io/pbrt/pbrt_tokenizer.h"

namespace ferry {
namespace {

std::optional<std::string> canonicalType(std::string_view t) {
  if (t == "bool" || t == "integer" || t == "float" || t == "point2" || t == "vector2" ||
      t == "point3" || t == "vector3" || t == "normal" || t == "rgb" || t == "spectrum" ||
      t == "blackbody" || t == "string" || t == "texture")
    return std::string(t);
  if (t == "point") return "point3";
  if (t == "vector") return "vector3";
  if (t == "normal3") return "normal";
  if (t == "color") return "rgb";
  return std::nullopt;
}

enum class ValueKind { Number, Integer, String, Bool, NumberOrString };

ValueKind valueKind(const std::string& type) {
  if (type == "integer") return ValueKind::Integer;
  if (type == "string" || type == "texture") return ValueKind::String;
  if (type == "bool") return ValueKind::Bool;
  if (type == "spectrum") return ValueKind::NumberOrString;
  return ValueKind::Number;
}

// Values per element: a point3 is three numbers.
size_t groupSize(const std::string& type) {
  if (type == "point2" || type == "vector2") return 2;
  if (type == "point3" || type == "vector3" || type == "normal" || type == "rgb") return 3;
  return 1;
}

// nan, inf, infinity in any case: a value, reported as not finite.
bool looksNonFinite(std::string_view s) {
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) s.remove_prefix(1);
  std::string lower(s);
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  return lower == "nan" || lower == "inf" || lower == "infinity";
}

}  // namespace

std::optional<double> parsePbrtNumber(std::string_view s) {
  if (s.size() > 1 && s[0] == '+') s.remove_prefix(1);
  double d = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
  if (s.empty() || end != s.data() + s.size()) return std::nullopt;
  if (ec == std::errc::result_out_of_range) {
    d = std::strtod(std::string(s).c_str(), nullptr);  // underflow: 0; overflow: inf
  } else if (ec != std::errc()) {
    return std::nullopt;
  }
  if (!std::isfinite(d)) return std::nullopt;
  return d;
}

size_t PbrtParam::size() const {
  return floats.size() + ints.size() + strings.size() + bools.size();
}

void PbrtParams::fail(const PbrtParam& p, const std::string& message) {
  throw InputError(p.where, fmt::format("\"{}\": {}", p.declaration(), message));
}

PbrtParams PbrtParams::parse(PbrtTokenSource& tokens) {
  PbrtParams params;
  while (tokens.peek().kind == PbrtToken::Kind::String) {
    const PbrtToken& decl = tokens.next();
    PbrtParam p;
    p.where = tokens.where(decl);
    // "type name": two words.
    std::string_view text = decl.text;
    std::vector<std::string_view> words;
    size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
      size_t b = i;
      while (i < text.size() && text[i] != ' ' && text[i] != '\t') ++i;
      if (i > b) words.push_back(text.substr(b, i - b));
    }
    if (words.size() != 2)
      throw InputError(p.where, fmt::format("expected a parameter declaration \"TYPE NAME\", found "
                                            "\"{}\"",
                                            decl.text));
    auto type = canonicalType(words[0]);
    if (!type)
      throw InputError(p.where,
                       fmt::format("unknown parameter type '{}' in \"{}\"", words[0], decl.text));
    p.type = *type;
    p.name = std::string(words[1]);
    const ValueKind kind = valueKind(p.type);

    auto addValue = [&](const PbrtToken& t) {
      // The location is made only for an error: values can number millions.
      auto bad = [&](const std::string& what) {
        throw InputError(tokens.where(t), fmt::format("\"{}\": {}", p.declaration(), what));
      };
      if (t.kind == PbrtToken::Kind::String) {
        if (kind == ValueKind::String || kind == ValueKind::NumberOrString) {
          if (!p.floats.empty()) bad("a spectrum is either numbers or one name, not both");
          p.strings.push_back(t.text);
        } else if (kind == ValueKind::Bool) {
          if (t.text == "true")
            p.bools.push_back(1);
          else if (t.text == "false")
            p.bools.push_back(0);
          else
            bad(fmt::format("expected true or false, found \"{}\"", t.text));
        } else {
          bad(fmt::format("expected a number, found the string \"{}\"", t.text));
        }
        return;
      }
      // A word: a number, or v4's bare true/false.
      if (kind == ValueKind::Bool) {
        if (t.text == "true")
          p.bools.push_back(1);
        else if (t.text == "false")
          p.bools.push_back(0);
        else
          bad(fmt::format("expected true or false, found '{}'", t.text));
        return;
      }
      if (kind == ValueKind::String)
        bad(fmt::format("expected a quoted string, found '{}'", t.text));
      std::optional<double> v = parsePbrtNumber(t.text);
      if (!v) {
        std::string lower = t.text;
        for (char& ch : lower) ch = char(std::tolower(static_cast<unsigned char>(ch)));
        if (lower.find("nan") != std::string::npos || lower.find("inf") != std::string::npos)
          bad(fmt::format("value '{}' is not finite", t.text));
        bad(fmt::format("expected a number, found '{}'", t.text));
      }
      if (kind == ValueKind::Integer) {
        if (*v != std::floor(*v)) bad(fmt::format("expected an integer, found '{}'", t.text));
        if (*v < INT32_MIN || *v > INT32_MAX)
          bad(fmt::format("integer '{}' does not fit in 32 bits", t.text));
        p.ints.push_back(int32_t(*v));
      } else {
        if (!p.strings.empty()) bad("a spectrum is either numbers or one name, not both");
        if (std::abs(*v) > 3.4e38) bad(fmt::format("value '{}' is too large for a float", t.text));
        p.floats.push_back(float(*v));
      }
    };

    const PbrtToken& first = tokens.peek();
    if (first.kind == PbrtToken::Kind::OpenBracket) {
      PbrtToken open = tokens.next();
      for (;;) {
        const PbrtToken& t = tokens.next();
        if (t.kind == PbrtToken::Kind::CloseBracket) break;
        if (t.kind == PbrtToken::Kind::End)
          throw InputError(
              tokens.where(open),
              fmt::format("\"{}\": '[' never closed (the file ends)", p.declaration()));
        if (t.kind == PbrtToken::Kind::OpenBracket)
          throw InputError(tokens.where(t), fmt::format("\"{}\": '[' inside a list (missing ']'?)",
                                                        p.declaration()));
        if (t.kind == PbrtToken::Kind::Word && !t.isNumber() && t.text != "true" &&
            t.text != "false" && kind != ValueKind::Bool && !looksNonFinite(t.text))
          throw InputError(tokens.where(t),
                           fmt::format("\"{}\": '{}' in a list of values (missing ']'?)",
                                       p.declaration(), t.text));
        addValue(t);
      }
    } else if (first.kind == PbrtToken::Kind::String ||
               (first.kind == PbrtToken::Kind::Word &&
                (first.isNumber() || first.text == "true" || first.text == "false" ||
                 looksNonFinite(first.text)))) {
      addValue(tokens.next());
    } else {
      throw InputError(p.where, fmt::format("\"{}\" has no value", p.declaration()));
    }
    if (p.size() == 0) fail(p, "empty list of values");
    size_t group = groupSize(p.type);
    if (group > 1 && p.floats.size() % group != 0)
      fail(p, fmt::format("{} numbers is not a multiple of {}", p.floats.size(), group));
    if (p.type == "spectrum" && !p.floats.empty() && p.floats.size() % 2 != 0)
      fail(p, "a spectrum needs wavelength-value pairs (an even count of numbers)");
    if (p.type == "spectrum" && p.strings.size() > 1) fail(p, "a spectrum takes one name or file");
    params.add(std::move(p));
  }
  return params;
}

void PbrtParams::add(PbrtParam param) {
  for (const PbrtParam& p : params_)
    if (p.name == param.name)
      throw InputError(param.where, fmt::format("parameter '{}' given twice (first at {})",
                                                param.name, p.where.toString()));
  params_.push_back(std::move(param));
}

const PbrtParam* PbrtParams::find(std::string_view name) const {
  for (const PbrtParam& p : params_)
    if (p.name == name) {
      p.used = true;
      return &p;
    }
  return nullptr;
}

bool PbrtParams::has(std::string_view name) const {
  for (const PbrtParam& p : params_)
    if (p.name == name) return true;
  return false;
}

float PbrtParams::getFloat(std::string_view name, float fallback) const {
  const PbrtParam* p = find(name);
  if (!p) return fallback;
  if (p->type == "integer" && p->ints.size() == 1) return float(p->ints[0]);
  if (p->type != "float") fail(*p, "expected a float");
  if (p->floats.size() != 1)
    fail(*p, fmt::format("expected one value, found {}", p->floats.size()));
  return p->floats[0];
}

int32_t PbrtParams::getInt(std::string_view name, int32_t fallback) const {
  const PbrtParam* p = find(name);
  if (!p) return fallback;
  if (p->type != "integer") fail(*p, "expected an integer");
  if (p->ints.size() != 1) fail(*p, fmt::format("expected one value, found {}", p->ints.size()));
  return p->ints[0];
}

bool PbrtParams::getBool(std::string_view name, bool fallback) const {
  const PbrtParam* p = find(name);
  if (!p) return fallback;
  if (p->type != "bool") fail(*p, "expected a bool");
  if (p->bools.size() != 1) fail(*p, fmt::format("expected one value, found {}", p->bools.size()));
  return p->bools[0] != 0;
}

std::string PbrtParams::getString(std::string_view name, const std::string& fallback) const {
  const PbrtParam* p = find(name);
  if (!p) return fallback;
  if (p->type != "string") fail(*p, "expected a string");
  if (p->strings.size() != 1)
    fail(*p, fmt::format("expected one value, found {}", p->strings.size()));
  return p->strings[0];
}

std::optional<Vec3f> PbrtParams::getPoint3(std::string_view name) const {
  const PbrtParam* p = find(name);
  if (!p) return std::nullopt;
  if (p->type != "point3" && p->type != "vector3" && p->type != "normal")
    fail(*p, "expected a point3");
  if (p->floats.size() != 3)
    fail(*p, fmt::format("expected one point, found {} numbers", p->floats.size()));
  return Vec3f(p->floats[0], p->floats[1], p->floats[2]);
}

const PbrtParam* PbrtParams::getArray(std::string_view name,
                                      std::initializer_list<std::string_view> types) const {
  const PbrtParam* p = find(name);
  if (!p) return nullptr;
  std::string list;
  for (std::string_view t : types) {
    if (p->type == t) return p;
    list += (list.empty() ? "" : " or ") + std::string(t);
  }
  fail(*p, fmt::format("expected {}", list));
}

std::vector<const PbrtParam*> PbrtParams::unused() const {
  std::vector<const PbrtParam*> out;
  for (const PbrtParam& p : params_)
    if (!p.used) out.push_back(&p);
  return out;
}

void PbrtParams::markAllUsed() const {
  for (const PbrtParam& p : params_) p.used = true;
}

void PbrtParams::addDefaults(const PbrtParams& defaults) {
  // Defaults apply where a directive reads them; unread ones are not worth
  // a warning (one `Attribute "shape"` serves spheres and meshes alike).
  for (const PbrtParam& d : defaults.params_)
    if (!has(d.name)) {
      params_.push_back(d);
      params_.back().used = true;
    }
}

}  // namespace ferry
