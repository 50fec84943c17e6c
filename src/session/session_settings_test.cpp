#include "session/session_settings.h"

#include <gtest/gtest.h>

namespace ferry {
namespace {

TEST(WorkerThreads, AskedForIsWhatRuns) {
  EXPECT_EQ(workerThreads(3, 2, 1), 3);
  EXPECT_EQ(workerThreads(1, 64, 8), 1);
}

TEST(WorkerThreads, ARankAloneOnItsMachineRunsEveryCore) {
  EXPECT_EQ(workerThreads(0, 2, 1), 2);
  EXPECT_EQ(workerThreads(0, 64, 1), 64);
  EXPECT_EQ(workerThreads(0, 0, 1), 1);  // no count known: one thread
}

TEST(WorkerThreads, RanksSharingAMachineRunTwiceItsCoresInAll) {
  EXPECT_EQ(workerThreads(0, 2, 2), 2);  // each may take the core the other leaves idle
  EXPECT_EQ(workerThreads(0, 2, 4), 1);
  EXPECT_EQ(workerThreads(0, 2, 8), 1);  // at least one each
  EXPECT_EQ(workerThreads(0, 64, 8), 16);
  EXPECT_EQ(workerThreads(0, 64, 3), 42);
  EXPECT_EQ(workerThreads(0, 4, 1), 4);
  EXPECT_EQ(workerThreads(0, 1, 2), 1);  // never more than the cores
}

}  // namespace
}  // namespace ferry
