// Numbers read from JSON files into a C++ type: a value that does not fit
// the type (a fraction for a count, a negative count, 2e82 for a byte
// count, 1e300 for a float) is refused, never converted (a conversion out
// of range is undefined behaviour).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>

#include <nlohmann/json.hpp>

namespace ferry {

// `v` as a T if it is a number that T holds (integers: whole and in range;
// floating point: finite and in range); nothing otherwise.
template <typename T>
std::optional<T> numberAs(const nlohmann::json& v) {
  using Limits = std::numeric_limits<T>;
  if constexpr (std::is_integral_v<T>) {
    if (v.is_number_unsigned()) {
      const uint64_t u = v.get<uint64_t>();
      if (u <= uint64_t(Limits::max())) return T(u);
    } else if (v.is_number_integer()) {
      const int64_t i = v.get<int64_t>();
      if (i >= int64_t(Limits::lowest()) && (i < 0 || uint64_t(i) <= uint64_t(Limits::max())))
        return T(i);
    }
  } else if (v.is_number()) {
    const double d = v.get<double>();
    if (std::isfinite(d) && std::abs(d) <= double(Limits::max())) return T(d);
  }
  return std::nullopt;
}

// numberAs, or a JSON type error (which the readers report with their file's path).
template <typename T>
T checkedNumber(const nlohmann::json& v) {
  if (const std::optional<T> n = numberAs<T>(v)) return *n;
  throw nlohmann::json::type_error::create(302,
                                           std::is_integral_v<T>
                                               ? "expected a whole number that fits"
                                               : "expected a finite number that fits",
                                           &v);
}

template <typename T>
T checkedNumber(const nlohmann::json& j, const char* key) {
  return checkedNumber<T>(j.at(key));
}

template <typename T>
T checkedNumberOr(const nlohmann::json& j, const char* key, T fallback) {
  return j.is_object() && j.contains(key) ? checkedNumber<T>(j.at(key)) : fallback;
}

}  // namespace ferry
