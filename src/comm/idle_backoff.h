// How long an idle rank waits for a message before it looks again: short at
// first (a reply is often on its way), longer while nothing comes, so that
// ranks outnumbering cores leave them to the ranks that have work.
#pragma once

#include <algorithm>
#include <chrono>

namespace ferry {

class IdleBackoff {
 public:
  std::chrono::microseconds next() {
    const auto wait = current_;
    current_ = std::min(current_ * 2, kLongest);
    return wait;
  }
  void reset() { current_ = kShortest; }

 private:
  static constexpr std::chrono::microseconds kShortest{10}, kLongest{500};
  std::chrono::microseconds current_ = kShortest;
};

}  // namespace ferry
