#include "core/clock.h"

namespace ferry {
namespace {

// Initialized before main() with the rest of the program's statics; nothing
// reads it during static initialization.
const Clock::time_point kProcessStart = Clock::now();

}  // namespace

Clock::time_point processStart() {
  return kProcessStart;
}

}  // namespace ferry
