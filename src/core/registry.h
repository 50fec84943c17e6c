// A registry of plug-ins by name (material models, geometry kinds): the
// built-in ones in their order, then those added at run time (a test's, an
// application's). Kind is a struct with a `std::string name`. Lookups and
// additions are thread-safe; a kind found stays where it is.
#pragma once

#include <deque>
#include <initializer_list>
#include <mutex>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

template <class Kind>
class Registry {
 public:
  // `what` names a kind in messages ("material model").
  Registry(std::string what, std::initializer_list<Kind> builtIn)
      : what_(std::move(what)), kinds_(builtIn) {}

  const std::deque<Kind>& all() const { return kinds_; }
  // Null if none has that name.
  const Kind* find(std::string_view name) const {
    std::lock_guard lock(mutex_);
    for (const Kind& k : kinds_)
      if (k.name == name) return &k;
    return nullptr;
  }
  // A name already taken is an InternalError.
  void add(Kind kind) {
    std::lock_guard lock(mutex_);
    for (const Kind& k : kinds_)
      if (k.name == kind.name)
        throw InternalError(fmt::format("{} \"{}\" is registered twice", what_, kind.name));
    kinds_.push_back(std::move(kind));
  }
  // "a, b, c": the names, for a message listing what there is.
  std::string names() const {
    std::lock_guard lock(mutex_);
    std::string out;
    for (const Kind& k : kinds_) out += (out.empty() ? "" : ", ") + k.name;
    return out;
  }

 private:
  std::string what_;
  std::deque<Kind> kinds_;
  mutable std::mutex mutex_;
};

}  // namespace ferry
