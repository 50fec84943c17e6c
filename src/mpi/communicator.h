// The one place Ferry talks to MPI. Everything above uses this small interface,
// so another transport touches only this file pair.
//
// Failure policy (nothing may hang): an error that every rank meets at the
// same point (bad flag, missing scene) is agreed on with agreeOnFailure() and
// all ranks exit cleanly with one message; an error on one rank in the middle
// of collective work calls abortAll(), which ends every rank within seconds.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace ferry {

class Communicator {
 public:
  // Initializes MPI if needed (thread level: funneled; TBB threads never call MPI).
  Communicator(int* argc, char*** argv);
  ~Communicator();
  Communicator(const Communicator&) = delete;
  Communicator& operator=(const Communicator&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool isRoot() const { return rank_ == 0; }

  void barrier() const;
  uint64_t sum(uint64_t value) const;
  double max(double value) const;
  std::vector<uint64_t> sum(std::span<const uint64_t> values) const;  // element-wise
  std::vector<double> sum(std::span<const double> values) const;
  std::vector<double> max(std::span<const double> values) const;
  // counts[r]: items for rank r; returns how many each rank sends to us.
  std::vector<int> exchangeCounts(const std::vector<int>& sendCounts) const;
  // All-to-all-v of raw bytes; counts and displacements in bytes.
  void exchangeBytes(const void* send, const std::vector<int>& sendCounts,
                     const std::vector<int>& sendOffsets, void* receive,
                     const std::vector<int>& receiveCounts,
                     const std::vector<int>& receiveOffsets) const;
  // Gathers variable-size byte blocks on rank 0 (receive ignored elsewhere).
  void gatherBytes(const void* send, int sendBytes, void* receive, const std::vector<int>& counts,
                   const std::vector<int>& offsets) const;
  std::vector<int> gatherInt(int value) const;  // on rank 0; empty elsewhere

  // Collective: true if any rank failed; then rank 0 prints one message (the
  // failing ranks' messages, merged when identical) to stderr.
  bool agreeOnFailure(bool failed, const std::string& message) const;
  // Makes a fatal signal on this rank (segfault, bus error, abort, ...) print
  // "ferry: rank R died of SIGNAME" before the default action, so the user
  // learns which rank failed; mpirun then ends the others.
  void reportFatalSignals() const;
  // Prints "ferry: error on rank R: message" and ends every rank (MPI_Abort).
  [[noreturn]] void abortAll(const std::string& message, int code = 1) const;

 private:
  int rank_ = 0;
  int size_ = 1;
  bool ownsMpi_ = false;
};

}  // namespace ferry
