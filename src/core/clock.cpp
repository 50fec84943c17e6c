#include "core/clock.h"

#include <ctime>

namespace ferry {
namespace {

// Initialized before main() with the rest of the program's statics; nothing
// reads it during static initialization.
const Clock::time_point kProcessStart = Clock::now();

}  // namespace

Clock::time_point processStart() {
  return kProcessStart;
}

double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + double(t.tv_nsec) * 1e-9;
}

}  // namespace ferry
