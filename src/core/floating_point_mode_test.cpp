// Every thread that shades runs in the one floating-point mode main() sets:
// TBB's workers and threads made later (in-process ranks). (After Embree
// builds too: trace/embree_backend_test.cpp.)
#include "core/floating_point_mode.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <limits>
#include <thread>

namespace ferry {
namespace {

// How many of `tasks` TBB tasks ran outside the mode.
int tasksOutsideTheMode(int tasks) {
  std::atomic<int> outside{0};
  tbb::parallel_for(0, tasks, [&](int) {
    if (!floatingPointModeIsFixed()) ++outside;
  });
  return outside.load();
}

TEST(FloatingPointMode, IsOnInTheMainThreadTbbWorkersAndLaterThreads) {
  EXPECT_TRUE(floatingPointModeIsFixed());
  EXPECT_EQ(tasksOutsideTheMode(10000), 0);
  bool inThread = false;
  int outsideFromThread = -1;
  std::thread t([&] {
    inThread = floatingPointModeIsFixed();
    outsideFromThread = tasksOutsideTheMode(10000);
  });
  t.join();
  EXPECT_TRUE(inThread);
  EXPECT_EQ(outsideFromThread, 0);
}

TEST(FloatingPointMode, FlushesDenormalsInWorkers) {
  // A denormal result (the smallest normal float halved) is zero in the mode.
  volatile float smallest = std::numeric_limits<float>::min();
  std::atomic<int> nonZero{0};
  tbb::parallel_for(0, 1000, [&](int) {
    volatile float half = smallest * 0.5f;
    if (half != 0.0f) ++nonZero;
  });
  EXPECT_EQ(nonZero.load(), 0);
}

}  // namespace
}  // namespace ferry
