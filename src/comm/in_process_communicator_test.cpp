#include "comm/in_process_communicator.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "comm/communicator_test_util.h"
#include "core/error.h"

namespace ferry {
namespace {

using namespace std::chrono_literals;

class InProcessCollectives : public ::testing::TestWithParam<int> {};

TEST_P(InProcessCollectives, RankAndSize) {
  const int n = GetParam();
  std::vector<int> seen(n, -1);
  runRanks(n, [&](const Communicator& comm) {
    EXPECT_EQ(comm.size(), n);
    seen[comm.rank()] = comm.rank();
  });
  for (int r = 0; r < n; ++r) EXPECT_EQ(seen[r], r);
}

TEST_P(InProcessCollectives, BarrierWaitsForEveryRank) {
  const int n = GetParam();
  std::atomic<int> arrived{0};
  runRanks(n, [&](const Communicator& comm) {
    if (comm.rank() == n - 1) std::this_thread::sleep_for(20ms);  // the last one is late
    ++arrived;
    comm.barrier();
    EXPECT_EQ(arrived.load(), n);
  });
}

TEST_P(InProcessCollectives, Reductions) {
  runRanks(GetParam(), testing::checkReductions);
}

// Sums of doubles add the ranks in rank order: 1e16 + 1 rounds back to 1e16
// (ties to even), so rank 0's 1e16 absorbs every later 1, where the reverse
// order would give 1e16 + (n - 1). Every rank gets the same bits.
TEST_P(InProcessCollectives, DoubleSumsAddInRankOrder) {
  const int n = GetParam();
  std::vector<std::array<double, 2>> results(n);
  runRanks(n, [&](const Communicator& comm) {
    std::vector<double> mine = {comm.isRoot() ? 1e16 : 1.0, 0.1 * (comm.rank() + 1)};
    std::vector<double> sums = comm.sum(std::span<const double>(mine));
    results[comm.rank()] = {sums[0], sums[1]};
  });
  double expected = 0.1;
  for (int r = 1; r < n; ++r) expected += 0.1 * (r + 1);
  for (int r = 0; r < n; ++r) {
    EXPECT_EQ(results[r][0], 1e16) << "rank " << r;
    EXPECT_EQ(results[r][1], expected) << "rank " << r;
  }
}

TEST_P(InProcessCollectives, ExchangeCounts) {
  runRanks(GetParam(), testing::checkExchangeCounts);
}

TEST_P(InProcessCollectives, ExchangeBytesWithUnevenCounts) {
  runRanks(GetParam(), testing::checkExchangeBytes);
}

TEST_P(InProcessCollectives, Gathers) {
  runRanks(GetParam(), testing::checkGathers);
}

TEST_P(InProcessCollectives, BroadcastFromRankZero) {
  runRanks(GetParam(), testing::checkBroadcast);
}

TEST_P(InProcessCollectives, NonBlockingMessagesAndSums) {
  runRanks(GetParam(), [](const Communicator& comm) { testing::checkMessages(comm, 5000); });
}

TEST_P(InProcessCollectives, AgreeOnFailure) {
  const int n = GetParam();
  std::vector<std::vector<bool>> agreed(n);
  ::testing::internal::CaptureStderr();  // one process: around all ranks
  runRanks(n, [&](const Communicator& comm) {
    agreed[comm.rank()] = testing::agreeOnFailureCases(comm);
  });
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), testing::agreeOnFailureCasesStderr(n));
  for (int r = 0; r < n; ++r) EXPECT_EQ(agreed[r], (std::vector<bool>{false, true, true}));
}

INSTANTIATE_TEST_SUITE_P(Ranks, InProcessCollectives, ::testing::Values(1, 2, 3, 5),
                         [](const auto& info) { return std::to_string(info.param) + "ranks"; });

// ------------------------------------------------------------------- failures

// The last rank aborts while the others loop in collectives; rank 0 (with
// more than two ranks) enters its first collective only after the abort. Every
// rank ends with the aborting rank's message, quickly.
class InProcessAbort : public ::testing::TestWithParam<int> {};

TEST_P(InProcessAbort, EndsEveryRank) {
  const int n = GetParam();
  std::mutex mutex;
  std::vector<std::string> messages(n);
  std::vector<double> secondsToEnd(n, -1);
  const auto start = std::chrono::steady_clock::now();
  auto sinceStart = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  try {
    runRanks(n, [&](const Communicator& comm) {
      const int me = comm.rank();
      try {
        if (me == n - 1) {
          std::this_thread::sleep_for(50ms);
          comm.abortAll("injected failure at exchange");
        }
        if (me == 0 && n > 2) std::this_thread::sleep_for(300ms);
        std::vector<int> counts(n, 0), offsets(n, 0);
        for (int round = 0;; ++round) {
          if (round % 2)
            comm.barrier();
          else
            comm.exchangeBytes(nullptr, counts, offsets, nullptr, counts, offsets);
        }
      } catch (const std::exception& e) {
        std::lock_guard lock(mutex);
        messages[me] = e.what();
        secondsToEnd[me] = sinceStart();
        throw;
      }
    });
    FAIL() << "runRanks returned normally";
  } catch (const GroupAborted& e) {
    EXPECT_EQ(e.abortingRank(), n - 1);
    EXPECT_EQ(e.rank(), n - 1);
    EXPECT_EQ(e.operation(), "abortAll");
    EXPECT_EQ(e.reason(), "injected failure at exchange");
  }
  for (int r = 0; r < n; ++r) {
    EXPECT_NE(messages[r].find(fmt::format("rank {} aborted: injected failure at exchange", n - 1)),
              std::string::npos)
        << "rank " << r << ": " << messages[r];
    EXPECT_LT(secondsToEnd[r], 1.0) << "rank " << r;
  }
}

INSTANTIATE_TEST_SUITE_P(Ranks, InProcessAbort, ::testing::Values(1, 2, 3, 5),
                         [](const auto& info) { return std::to_string(info.param) + "ranks"; });

// Ranks that only poll for messages and sums (the overlapped exchange's idle
// loop) end within a second when another rank aborts.
TEST(InProcessFailure, AbortEndsRanksThatPollForMessages) {
  const auto start = std::chrono::steady_clock::now();
  std::atomic<int> ended{0};
  EXPECT_THROW(runRanks(3,
                        [&](const Communicator& comm) {
                          try {
                            if (comm.rank() == 2) {
                              std::this_thread::sleep_for(50ms);
                              comm.abortAll("injected failure while rays are in flight");
                            }
                            SumHandle sum = comm.startSum({1});
                            std::vector<uint64_t> result;
                            for (;;) {
                              while (comm.receive<int, int>()) {
                              }
                              comm.sumDone(sum, result);
                              comm.waitForMessage(std::chrono::milliseconds(5));
                            }
                          } catch (const GroupAborted&) {
                            ++ended;
                            throw;
                          }
                        }),
               GroupAborted);
  EXPECT_EQ(ended.load(), 3);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
}

// A message that is not a header plus whole items is an error, not garbage.
TEST(InProcessFailure, MalformedMessageThrows) {
  runRanks(2, [](const Communicator& comm) {
    if (comm.rank() == 0) {
      const uint8_t bytes[3] = {1, 2, 3};
      comm.send(1, int32_t(7), std::span<const uint8_t>(bytes));
    }
    comm.barrier();
    if (comm.rank() == 1) {
      try {
        comm.receive<int32_t, uint16_t>();
        ADD_FAILURE() << "a 7-byte message read as 4 + 2k bytes did not throw";
      } catch (const CommunicationError& e) {
        EXPECT_NE(std::string(e.what()).find("7 bytes from rank 0"), std::string::npos) << e.what();
      }
    }
  });
}

// A rank whose work throws (without calling abortAll) ends the others too,
// and runRanks rethrows that exception, not the others' GroupAborted.
TEST(InProcessFailure, ThrowingRankEndsTheOthers) {
  std::atomic<int> aborted{0};
  try {
    runRanks(3, [&](const Communicator& comm) {
      if (comm.rank() == 1) throw InputError("missing.obj: no such file");
      try {
        comm.barrier();
      } catch (const GroupAborted& e) {
        EXPECT_EQ(e.abortingRank(), 1);
        ++aborted;
        throw;
      }
    });
    FAIL() << "runRanks returned normally";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "missing.obj: no such file");
  }
  EXPECT_EQ(aborted.load(), 2);
}

TEST(InProcessFailure, MismatchedCollectivesThrowInsteadOfHanging) {
  std::atomic<int> mismatches{0};
  EXPECT_THROW(runRanks(2,
                        [&](const Communicator& comm) {
                          try {
                            if (comm.isRoot())
                              comm.barrier();
                            else
                              comm.sum(uint64_t(1));
                          } catch (const CommunicationError& e) {
                            EXPECT_NE(std::string(e.what()).find("do not match"), std::string::npos)
                                << e.what();
                            ++mismatches;
                            throw;
                          }
                        }),
               CommunicationError);
  EXPECT_EQ(mismatches.load(), 2);
  // Rank 0 returns while rank 1 waits in one more collective.
  EXPECT_THROW(runRanks(2,
                        [](const Communicator& comm) {
                          if (!comm.isRoot()) comm.barrier();
                        }),
               CommunicationError);
}

TEST(InProcessFailure, ByteCountsThatDisagreeThrow) {
  try {
    runRanks(2, [](const Communicator& comm) {
      std::vector<char> send(8), receive(8);
      std::vector<int> sendCounts = {2, 2}, offsets = {0, 4};
      std::vector<int> receiveCounts = {2, comm.isRoot() ? 3 : 2};  // rank 0 expects 3 from rank 1
      comm.exchangeBytes(send.data(), sendCounts, offsets, receive.data(), receiveCounts, offsets);
    });
    FAIL() << "runRanks returned normally";
  } catch (const CommunicationError& e) {
    EXPECT_EQ(e.operation(), "exchangeBytes");
    EXPECT_EQ(e.rank(), 0);
    EXPECT_STREQ(e.what(), "exchangeBytes on rank 0: rank 1 sends 2 bytes, this rank expects 3");
  }
  EXPECT_THROW(runRanks(3,
                        [](const Communicator& comm) {
                          std::vector<double> values(comm.rank() == 2 ? 1 : 2, 1.0);
                          comm.sum(std::span<const double>(values));
                        }),
               CommunicationError);
}

}  // namespace
}  // namespace ferry
