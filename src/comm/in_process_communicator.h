// N ranks as N threads of one process (tests, the bandwidth predictor, one
// rank started without a launcher): the distributed traversal, the
// compositor and anything else written against Communicator run unchanged,
// without mpirun.
//
//   runRanks(3, [&](const Communicator& comm) { ... one rank's work ... });
//
// Results are deterministic and the same on every rank: every collective
// reads the ranks' contributions in rank order (a floating-point sum is
// v0 + v1 + v2 + ...). Nothing hangs: abortAll() throws GroupAborted in the
// caller and in every rank in a collective or entering one; a rank that
// returns while others wait in a collective it will never join, or arguments
// that do not match across ranks, make them throw CommunicationError.
// docs/architecture.md, "Two communicators".
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "comm/communicator.h"

namespace ferry {

// The group was aborted: thrown in the rank that called abortAll (operation
// "abortAll") and in every other rank from the collective it was in or entered.
class GroupAborted : public CommunicationError {
 public:
  GroupAborted(std::string operation, int rank, int abortingRank, const std::string& reason);
  int abortingRank() const { return abortingRank_; }
  const std::string& reason() const { return reason_; }  // abortAll's message

 private:
  int abortingRank_;
  std::string reason_;
};

struct InProcessHub;  // the shared rendezvous (in the .cpp)

class InProcessCommunicator final : public Communicator {
 public:
  int rank() const override { return rank_; }
  int size() const override;
  const char* transport() const override { return "in-process"; }

  void barrier() const override;
  uint64_t sum(uint64_t value) const override;
  double max(double value) const override;
  std::vector<uint64_t> sum(std::span<const uint64_t> values) const override;
  std::vector<double> sum(std::span<const double> values) const override;
  std::vector<double> max(std::span<const double> values) const override;
  std::vector<int> exchangeCounts(const std::vector<int>& sendCounts) const override;
  void exchangeBytes(const void* send, const std::vector<int>& sendCounts,
                     const std::vector<int>& sendOffsets, void* receive,
                     const std::vector<int>& receiveCounts,
                     const std::vector<int>& receiveOffsets) const override;
  void gatherBytes(const void* send, int sendBytes, void* receive, const std::vector<int>& counts,
                   const std::vector<int>& offsets) const override;
  std::vector<int> gatherInt(int value) const override;
  void broadcastBytes(std::span<std::byte> bytes) const override;
  std::unique_ptr<Communicator> split(int color) const override;

  // Messages are delivered at once into the receiver's inbox (a send is
  // complete when it returns); a rank waiting for messages sleeps on the
  // hub's condition variable. Sums complete when the last rank contributes.
  SendHandle sendBytes(int to, std::vector<std::byte> bytes) const override;
  std::optional<ReceivedBytes> receiveBytes() const override;
  bool sendDone(SendHandle handle) const override;
  bool allSendsDone() const override;
  void waitForMessage(std::chrono::microseconds timeout) const override;
  SumHandle startSum(std::vector<uint64_t> values) const override;
  bool sumDone(SumHandle handle, std::vector<uint64_t>& result) const override;

 private:
  // abortAll: marks the group failed, wakes every rank, and throws
  // GroupAborted here. Prints nothing and ends no process (the exit code has
  // no meaning in one).
  void abortEveryRank(const std::string& message, int code) const override;

  friend class InProcessGroup;
  InProcessCommunicator(InProcessHub& hub, int rank) : hub_(hub), rank_(rank) {}

  InProcessHub& hub_;
  int rank_;
};

// The ranks of one in-process run and their shared rendezvous. Each rank's
// communicator is used by that rank's thread only (as MPI's funneled level:
// TBB threads inside a rank never call it).
class InProcessGroup {
 public:
  explicit InProcessGroup(int size);
  ~InProcessGroup();
  InProcessGroup(const InProcessGroup&) = delete;
  InProcessGroup& operator=(const InProcessGroup&) = delete;

  int size() const;
  const Communicator& communicator(int rank) const;
  // Rank `rank`'s work has ended normally. A collective that other ranks wait
  // in (or enter later) can then never complete: they throw CommunicationError.
  void leave(int rank);
  // Ends the group as abortAll does, without throwing (for a rank whose work
  // threw). The first abort is the one every rank reports.
  void abort(int rank, const std::string& message);
  // The rank that aborted first, or -1.
  int abortingRank() const;

 private:
  std::unique_ptr<InProcessHub> hub_;
  std::vector<std::unique_ptr<InProcessCommunicator>> communicators_;
};

// Runs body(communicator of rank r) for r = 0..ranks-1, each on its own
// thread, and waits for all of them. A rank whose body throws aborts the group
// (so the others end too); then the exception that ended the group (the
// aborting rank's) is rethrown here.
void runRanks(int ranks, const std::function<void(const Communicator&)>& body);

}  // namespace ferry
