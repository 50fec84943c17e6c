// The test binary's main: the process starts as `ferry` does (one
// floating-point mode for every thread, set before any thread or TBB call),
// so tests see the numbers the renderer computes.
#include <gtest/gtest.h>

#include "core/floating_point_mode.h"

int main(int argc, char** argv) {
  ferry::useFixedFloatingPointMode();
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
