// The one clock for stage and frame timings: monotonic, in seconds.
#pragma once

#include <chrono>

namespace ferry {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// When this process started, as near as the program can tell: read during
// static initialization, before main() (so before MPI's start-up), after the
// dynamic loader. What a rank's time to first pixel is counted from.
Clock::time_point processStart();

// CPU time this process has used so far, every thread, user and system, in
// seconds. Beside wall-clock times it tells work from waiting: ranks that
// time-slice the same cores stretch each other's wall clock, not their CPU time.
double processCpuSeconds();

}  // namespace ferry
