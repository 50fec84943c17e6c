// Errors that reach the user. An InputError names where the bad input is
// (file, line, column when known) so the message can be acted upon.
#pragma once

#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include <fmt/format.h>

namespace ferry {

struct SourceLocation {
  std::string file;
  int line = 0;    // 1-based; 0 when unknown
  int column = 0;  // 1-based; 0 when unknown
  std::string toString() const {
    if (file.empty()) return {};
    if (line <= 0) return file;
    if (column <= 0) return fmt::format("{}:{}", file, line);
    return fmt::format("{}:{}:{}", file, line, column);
  }
};

// Bad input from the user: a file, a flag, a scene description.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
  InputError(const SourceLocation& where, const std::string& message)
      : std::runtime_error(where.toString().empty() ? message : where.toString() + ": " + message),
        where_(where) {}
  const SourceLocation& where() const { return where_; }

 private:
  SourceLocation where_;
};

// An internal invariant failed: a bug in Ferry, not in the input.
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

namespace check_detail {

// Integers compare by value whatever their signedness (std::cmp_*), so a
// size() checked against an int needs no cast and a negative int is never
// "greater" than a size; anything else compares with its own operator.
template <typename T>
concept Integer = std::is_integral_v<T> && !std::is_same_v<T, bool> && !std::is_same_v<T, char> &&
                  !std::is_same_v<T, wchar_t> && !std::is_same_v<T, char8_t> &&
                  !std::is_same_v<T, char16_t> && !std::is_same_v<T, char32_t>;

enum class Op { Eq, Ne, Lt, Le, Gt, Ge };

template <Op op, typename A, typename B>
constexpr bool holds(const A& a, const B& b) {
  if constexpr (Integer<A> && Integer<B>) {
    if constexpr (op == Op::Eq) return std::cmp_equal(a, b);
    if constexpr (op == Op::Ne) return std::cmp_not_equal(a, b);
    if constexpr (op == Op::Lt) return std::cmp_less(a, b);
    if constexpr (op == Op::Le) return std::cmp_less_equal(a, b);
    if constexpr (op == Op::Gt) return std::cmp_greater(a, b);
    if constexpr (op == Op::Ge) return std::cmp_greater_equal(a, b);
  } else {
    if constexpr (op == Op::Eq) return a == b;
    if constexpr (op == Op::Ne) return a != b;
    if constexpr (op == Op::Lt) return a < b;
    if constexpr (op == Op::Le) return a <= b;
    if constexpr (op == Op::Gt) return a > b;
    if constexpr (op == Op::Ge) return a >= b;
  }
}

template <typename T>
std::string operand(const T& value) {
  if constexpr (fmt::is_formattable<T>::value)
    return fmt::format("{}", value);
  else
    return "(not formattable)";
}

template <typename A, typename B>
[[noreturn, gnu::cold, gnu::noinline]] void fail(const char* expression, const A& a, const B& b,
                                                 const char* file, int line) {
  throw InternalError(fmt::format("check failed: {} ({} vs {}) at {}:{}", expression, operand(a),
                                  operand(b), file, line));
}

}  // namespace check_detail
}  // namespace ferry

// Checks an invariant and reports the expression and location when it fails.
#define FERRY_CHECK(cond)                                                       \
  do {                                                                          \
    if (!(cond))                                                                \
      throw ::ferry::InternalError(                                             \
          fmt::format("check failed: {} at {}:{}", #cond, __FILE__, __LINE__)); \
  } while (0)

// Comparison checks, which also report both operands (formatted with fmt when
// they can be): "check failed: hits.size() == rays.size() (12 vs 13) at
// file:line". Each operand is evaluated once.
#define FERRY_CHECK_EQ(a, b) FERRY_CHECK_OP_(Eq, ==, a, b)
#define FERRY_CHECK_NE(a, b) FERRY_CHECK_OP_(Ne, !=, a, b)
#define FERRY_CHECK_LT(a, b) FERRY_CHECK_OP_(Lt, <, a, b)
#define FERRY_CHECK_LE(a, b) FERRY_CHECK_OP_(Le, <=, a, b)
#define FERRY_CHECK_GT(a, b) FERRY_CHECK_OP_(Gt, >, a, b)
#define FERRY_CHECK_GE(a, b) FERRY_CHECK_OP_(Ge, >=, a, b)

#define FERRY_CHECK_OP_(op, symbol, a, b)                                                         \
  do {                                                                                            \
    const auto& ferryCheckA_ = (a);                                                               \
    const auto& ferryCheckB_ = (b);                                                               \
    if (!::ferry::check_detail::holds<::ferry::check_detail::Op::op>(ferryCheckA_, ferryCheckB_)) \
      ::ferry::check_detail::fail(#a " " #symbol " " #b, ferryCheckA_, ferryCheckB_, __FILE__,    \
                                  __LINE__);                                                      \
  } while (0)
