// The Communicator over MPI (MPI_COMM_WORLD): the one place Ferry talks to
// MPI, so another transport touches only this folder. mpi.h stays in the .cpp.
//
// MPI errors come back as codes (MPI_ERRORS_RETURN) and are thrown as
// CommunicationError naming the MPI call, the rank and MPI's own message,
// rather than killing the job without a word.
#pragma once

#include <memory>

#include "comm/communicator.h"

namespace ferry {

// An application's own communicator, by its Fortran handle (MPI_Comm_c2f;
// mpi4py's Comm.py2f): a plain int, so no header outside mpi/ needs mpi.h.
struct ApplicationCommunicator {
  int fortranHandle = 0;
};

class MpiCommunicator final : public Communicator {
 public:
  // Over MPI_COMM_WORLD. Initializes MPI if needed (thread level: funneled;
  // TBB threads never call MPI) and finalizes it on destruction if it did.
  MpiCommunicator(int* argc, char*** argv);
  // Over the ranks of an application's communicator (MPI already running;
  // never finalized here). Ferry talks on duplicates of it, never on it.
  explicit MpiCommunicator(ApplicationCommunicator application);
  ~MpiCommunicator() override;
  MpiCommunicator(const MpiCommunicator&) = delete;
  MpiCommunicator& operator=(const MpiCommunicator&) = delete;

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  const char* transport() const override { return "mpi"; }
  // MPI_Comm_split_type(MPI_COMM_TYPE_SHARED) of the job's communicator;
  // a group (split) keeps the job's count.
  int ranksOnThisMachine() const override { return ranksOnMachine_; }

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

  // Not collective. Makes a fatal signal on this rank (segfault, bus error,
  // abort, ...) print "ferry: rank R died of SIGNAME" before the default
  // action, so the user learns which rank failed; mpirun then ends the
  // others. (Not part of Communicator: in one process a signal ends every
  // rank at once.)
  void reportFatalSignals() const;

  // Point-to-point messages go over a duplicate of MPI_COMM_WORLD (so they
  // never match anything else), MPI_Isend and MPI_Improbe/MPI_Mrecv; a
  // message larger than `maxPieceBytes` (1 GiB: MPI counts are ints) goes as
  // a length and pieces. Sums are MPI_Iallreduce; progress is made whenever
  // one of these is called (the funneled thread level: one thread calls MPI).
  SendHandle sendBytes(int to, std::vector<std::byte> bytes) const override;
  std::optional<ReceivedBytes> receiveBytes() const override;
  bool sendDone(SendHandle handle) const override;
  bool allSendsDone() const override;
  void waitForMessage(std::chrono::microseconds timeout) const override;
  SumHandle startSum(std::vector<uint64_t> values) const override;
  bool sumDone(SumHandle handle, std::vector<uint64_t>& result) const override;
  // For tests: split messages above this many bytes (every rank alike).
  void setMaxPieceBytes(size_t bytes) { maxPieceBytes_ = bytes; }

 private:
  struct Messaging;  // MPI requests and buffers in flight (in the .cpp, with mpi.h)
  // Over the communicator at `communicator` (an MPI_Comm*, freed by the
  // caller), part of a job whose rank `jobRank` this process is, with
  // `ranksOnMachine` of its ranks on this machine.
  MpiCommunicator(const void* communicator, int jobRank, int ranksOnMachine);
  // Tests every send in flight, releasing the completed ones.
  void progressSends() const;
  // Prints "ferry: error on rank R: message" and ends every rank (MPI_Abort).
  void abortEveryRank(const std::string& message, int code) const override;
  // Duplicates the communicator at `communicator` (an MPI_Comm*) for the
  // collectives and the messages; learns the rank and size.
  void join(const void* communicator);
  // Counts the ranks of the joined communicator on this machine (collective).
  void countRanksOnMachine();
  // Throws a CommunicationError unless `code` is MPI_SUCCESS.
  void check(int code, const char* operation) const;

  int rank_ = -1;  // until MPI_Comm_rank answers (errors before it name no rank)
  int size_ = 1;
  int jobRank_ = -1;  // what messages call this rank: its rank in the whole job
  bool ownsMpi_ = false;
  int ranksOnMachine_ = 1;
  size_t maxPieceBytes_ = size_t(1) << 30;
  std::unique_ptr<Messaging> messaging_;
};

}  // namespace ferry
