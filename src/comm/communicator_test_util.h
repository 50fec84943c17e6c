// Shared by the communicator tests only (included from *_test.cpp): what
// every Communicator must do, as checks one rank runs with its communicator.
// in_process_communicator_test.cpp runs them on 1, 2, 3 and 5 threads;
// mpi_communicator_test.cpp on the MPI ranks it is started with (one under
// ctest, three under tests/tools/run_mpi_unit_tests.sh), so both
// implementations keep the same contract.
//
// Only EXPECT_*: a check that stopped early on one rank would leave the
// others waiting in a collective.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "comm/communicator.h"

namespace ferry::testing {

inline void checkReductions(const Communicator& comm) {
  const int n = comm.size(), r = comm.rank();
  EXPECT_EQ(comm.isRoot(), r == 0);
  EXPECT_EQ(comm.sum(uint64_t(r + 1)), uint64_t(n * (n + 1) / 2));
  // The largest value sits on a middle rank.
  EXPECT_EQ(comm.max(r == n / 2 ? 100.5 : -double(r)), 100.5);

  std::vector<uint64_t> counts = {uint64_t(r), uint64_t(10 * r), 7};
  EXPECT_EQ(comm.sum(std::span<const uint64_t>(counts)),
            (std::vector<uint64_t>{uint64_t(n * (n - 1) / 2), uint64_t(10 * n * (n - 1) / 2),
                                   uint64_t(7 * n)}));
  // Small integers: exact in any summation order.
  std::vector<double> values = {double(r), -double(r), r == 0 ? 3.0 : 0.5};
  EXPECT_EQ(comm.sum(std::span<const double>(values)),
            (std::vector<double>{n * (n - 1) / 2.0, -n * (n - 1) / 2.0, 3.0 + 0.5 * (n - 1)}));
  EXPECT_EQ(comm.max(std::span<const double>(values)),
            (std::vector<double>{double(n - 1), 0.0, 3.0}));
  comm.barrier();
}

inline void checkExchangeCounts(const Communicator& comm) {
  const int n = comm.size();
  std::vector<int> send(n);
  for (int d = 0; d < n; ++d) send[d] = 100 * comm.rank() + d;
  std::vector<int> received = comm.exchangeCounts(send);
  EXPECT_EQ(int(received.size()), n);
  for (int s = 0; s < n && s < int(received.size()); ++s)
    EXPECT_EQ(received[s], 100 * s + comm.rank());
}

// What rank `from` sends rank `to` in checkExchangeBytes: a few bytes, often
// none (to itself too).
inline int bytesBetween(int from, int to) {
  return (from + 2 * to) % 4;
}
inline std::byte payload(int from, int to, int i) {
  return std::byte(16 * from + 4 * to + i);
}

// Uneven counts, zeros included; the sender's blocks in reverse rank order and
// the receiver's with a gap after each, which must stay untouched.
inline void checkExchangeBytes(const Communicator& comm) {
  const int n = comm.size(), me = comm.rank();
  std::vector<int> sendCounts(n), sendOffsets(n), receiveCounts(n), receiveOffsets(n);
  std::vector<std::byte> send;
  for (int d = n - 1; d >= 0; --d) {
    sendCounts[d] = bytesBetween(me, d);
    sendOffsets[d] = int(send.size());
    for (int i = 0; i < sendCounts[d]; ++i) send.push_back(payload(me, d, i));
  }
  int receiveBytes = 0;
  for (int s = 0; s < n; ++s) {
    receiveCounts[s] = bytesBetween(s, me);
    receiveOffsets[s] = receiveBytes;
    receiveBytes += receiveCounts[s] + 1;
  }
  const std::byte gap{0xee};
  std::vector<std::byte> receive(receiveBytes, gap);
  comm.exchangeBytes(send.data(), sendCounts, sendOffsets, receive.data(), receiveCounts,
                     receiveOffsets);
  for (int s = 0; s < n; ++s) {
    for (int i = 0; i < receiveCounts[s]; ++i)
      EXPECT_EQ(receive[receiveOffsets[s] + i], payload(s, me, i))
          << "from rank " << s << " byte " << i;
    EXPECT_EQ(receive[receiveOffsets[s] + receiveCounts[s]], gap);
  }
}

inline void checkGathers(const Communicator& comm) {
  const int n = comm.size(), me = comm.rank();
  std::vector<int> squares = comm.gatherInt(me * me);
  std::vector<int> expectedSquares;
  if (comm.isRoot())
    for (int r = 0; r < n; ++r) expectedSquares.push_back(r * r);
  EXPECT_EQ(squares, expectedSquares);

  // Rank r sends r bytes of value r (rank 0 none); rank 0 places them from the end.
  std::vector<uint8_t> mine(me, uint8_t(me));
  std::vector<int> counts, offsets;
  std::vector<uint8_t> all;
  if (comm.isRoot()) {
    counts.resize(n);
    offsets.resize(n);
    int total = n * (n - 1) / 2;
    all.assign(total, 0xff);
    for (int r = 0; r < n; ++r) {
      counts[r] = r;
      total -= r;
      offsets[r] = total;
    }
  }
  comm.gatherBytes(mine.data(), int(mine.size()), all.data(), counts, offsets);
  std::vector<uint8_t> expected;
  if (comm.isRoot())
    for (int r = n - 1; r >= 0; --r) expected.insert(expected.end(), r, uint8_t(r));
  EXPECT_EQ(all, expected);
}

// Plain data, as a camera change the viewer will send from rank 0.
struct CameraChange {
  double position[3];
  float fieldOfView;
  int32_t frame;
};

inline void checkBroadcast(const Communicator& comm) {
  CameraChange change{};
  std::vector<float> values(5, -1.0f);
  if (comm.isRoot()) {
    change = {{1.5, -2.25, 1e10}, 45.0f, 17};
    values = {0.5f, 1.5f, 2.5f, 3.5f, 4.5f};
  }
  comm.broadcast(change);
  comm.broadcast(std::span<float>(values));
  EXPECT_EQ(change.position[0], 1.5);
  EXPECT_EQ(change.position[1], -2.25);
  EXPECT_EQ(change.position[2], 1e10);
  EXPECT_EQ(change.fieldOfView, 45.0f);
  EXPECT_EQ(change.frame, 17);
  EXPECT_EQ(values, (std::vector<float>{0.5f, 1.5f, 2.5f, 3.5f, 4.5f}));
  std::vector<float> none;
  comm.broadcast(std::span<float>(none));  // an empty broadcast is still collective
}

// What checkMessages sends: a header naming sender and sequence, items
// that are a function of both.
struct MessageHeader {
  int32_t from;
  int32_t sequence;
};
inline uint64_t messageItem(int from, int to, int sequence, size_t i) {
  return uint64_t(from) << 48 | uint64_t(to) << 40 | uint64_t(sequence) << 32 | uint64_t(i);
}
// Items of message `sequence` from `from` to `to`: none, a few, or
// `largeItems` (larger than the MPI implementation's piece when a test lowers it).
inline size_t messageItems(int from, int to, int sequence, size_t largeItems) {
  return sequence == 0 ? 0 : sequence == 1 ? size_t(1 + from + to) : largeItems;
}

// Non-blocking messages: every rank sends three messages to every other
// rank and receives its own, in the order each sender sent them; then two
// overlapping non-blocking sums. Polls with waitForMessage, never blocks;
// gives up (failing) after 20 s.
inline void checkMessages(const Communicator& comm, size_t largeItems) {
  const int n = comm.size(), me = comm.rank();
  std::vector<SendHandle> sent;
  for (int sequence = 0; sequence < 3; ++sequence)
    for (int to = 0; to < n; ++to) {
      if (to == me) continue;
      std::vector<uint64_t> items(messageItems(me, to, sequence, largeItems));
      for (size_t i = 0; i < items.size(); ++i) items[i] = messageItem(me, to, sequence, i);
      sent.push_back(comm.send(to, MessageHeader{me, sequence}, std::span<const uint64_t>(items)));
    }
  std::vector<int> next(n, 0);  // per sender: the sequence number expected next
  int received = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (received < 3 * (n - 1) && std::chrono::steady_clock::now() < deadline) {
    auto message = comm.receive<MessageHeader, uint64_t>();
    if (!message) {
      comm.waitForMessage(std::chrono::microseconds(200));
      continue;
    }
    ++received;
    const int from = message->from;
    EXPECT_EQ(message->header.from, from);
    EXPECT_NE(from, me);
    if (from < 0 || from >= n) continue;
    const int sequence = next[from]++;
    EXPECT_EQ(message->header.sequence, sequence) << "from rank " << from;
    ASSERT_EQ(message->items.size(), messageItems(from, me, sequence, largeItems));
    for (size_t i = 0; i < message->items.size(); ++i)
      if (message->items[i] != messageItem(from, me, sequence, i)) {
        ADD_FAILURE() << "item " << i << " of message " << sequence << " from rank " << from;
        break;
      }
  }
  EXPECT_EQ(received, 3 * (n - 1));
  while (!comm.allSendsDone() && std::chrono::steady_clock::now() < deadline)
    comm.waitForMessage(std::chrono::microseconds(100));
  for (SendHandle h : sent) EXPECT_TRUE(comm.sendDone(h));

  // Two sums in flight at once; ranks start them at different times.
  SumHandle first = comm.startSum({uint64_t(me), 1});
  comm.waitForMessage(std::chrono::microseconds(100 * me));
  SumHandle second = comm.startSum({uint64_t(10 * me)});
  std::vector<uint64_t> a, b;
  bool firstDone = false, secondDone = false;
  while (!(firstDone && secondDone) && std::chrono::steady_clock::now() < deadline) {
    if (!firstDone) firstDone = comm.sumDone(first, a);
    if (!secondDone) secondDone = comm.sumDone(second, b);
    comm.waitForMessage(std::chrono::microseconds(50));
  }
  EXPECT_EQ(a, (std::vector<uint64_t>{uint64_t(n * (n - 1) / 2), uint64_t(n)}));
  EXPECT_EQ(b, (std::vector<uint64_t>{uint64_t(10 * n * (n - 1) / 2)}));
  comm.barrier();
}

// agreeOnFailure's three cases in turn: no rank fails, only the last one
// fails, every rank fails alike. Returns what this rank agreed in each.
inline std::vector<bool> agreeOnFailureCases(const Communicator& comm) {
  const bool last = comm.rank() == comm.size() - 1;
  return {comm.agreeOnFailure(false, ""),
          comm.agreeOnFailure(last, last ? "scene.obj: no such file" : ""),
          comm.agreeOnFailure(true, "--size '12by3': expected WIDTHxHEIGHT")};
}
// What rank 0 prints to stderr over those cases (the other ranks: nothing):
// the failing rank named once, then one message without ranks.
inline std::string agreeOnFailureCasesStderr(int ranks) {
  std::string out =
      ranks == 1 ? "ferry: error: scene.obj: no such file\n"
                 : fmt::format("ferry: error on rank {}: scene.obj: no such file\n", ranks - 1);
  return out + "ferry: error: --size '12by3': expected WIDTHxHEIGHT\n";
}

}  // namespace ferry::testing
