// Errors that reach the user. An InputError names where the bad input is
// (file, line, column when known) so the message can be acted upon.
#pragma once

#include <stdexcept>
#include <string>

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

}  // namespace ferry

// Checks an invariant and reports the expression and location when it fails.
#define FERRY_CHECK(cond)                                                      \
  do {                                                                         \
    if (!(cond))                                                               \
      throw ::ferry::InternalError(                                            \
          fmt::format("check failed: {} ({}:{})", #cond, __FILE__, __LINE__)); \
  } while (0)
