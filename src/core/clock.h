// The one clock for stage and frame timings: monotonic, in seconds.
#pragma once

#include <chrono>

namespace ferry {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace ferry
