// How ranks talk: the collectives Ferry's distributed layer is written
// against. Implemented by MpiCommunicator (mpi_communicator.h, the only code
// that names MPI) and InProcessCommunicator (in_process_communicator.h, N
// ranks as N threads of one process; tests run without mpirun).
//
// Every operation is collective unless it says otherwise: every rank calls it,
// in the same order, with matching arguments. Callers take a `const
// Communicator&`; the operations change no state a caller can see.
//
// Failure policy (nothing may hang): an error that every rank meets at the
// same point (bad flag, missing scene) is agreed on with agreeOnFailure() and
// all ranks exit cleanly with one message; an error on one rank in the middle
// of collective work calls abortAll(), which ends every rank within seconds.
// A collective that fails underneath (MPI returns an error code) throws a
// CommunicationError naming the operation and the rank.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace ferry {

// A collective failed on this rank (an MPI error code, or in-process: another
// rank aborted, or the ranks' arguments do not match).
class CommunicationError : public std::runtime_error {
 public:
  // what(): "OPERATION on rank RANK: DETAIL" (rank -1: not known yet, as
  // when MPI fails to start; then "OPERATION: DETAIL").
  CommunicationError(std::string operation, int rank, const std::string& detail);
  const std::string& operation() const { return operation_; }
  int rank() const { return rank_; }

 private:
  std::string operation_;
  int rank_;
};

// A message that arrived (non-blocking messages, below): who sent it and its bytes.
struct ReceivedBytes {
  int from = -1;
  std::vector<std::byte> bytes;
};
// A message that arrived, typed: the sender's header and items.
template <typename Header, typename Item>
struct Received {
  int from = -1;
  Header header;
  std::vector<Item> items;
};
// A send started by Communicator::send, to ask whether it has completed.
struct SendHandle {
  uint64_t id = 0;
};
// A non-blocking sum started by Communicator::startSum.
struct SumHandle {
  uint64_t id = 0;
};

class Communicator {
 public:
  virtual ~Communicator() = default;

  // Not collective.
  virtual int rank() const = 0;
  virtual int size() const = 0;
  // How the ranks talk: "mpi", or "in-process" (ranks as threads of one
  // process; one rank started without a launcher, mpi/launcher.h).
  virtual const char* transport() const = 0;
  bool isRoot() const { return rank() == 0; }
  // How many ranks of the job run on this rank's machine and share its
  // cores (counted when the job's communicator was made); 1 for ranks that
  // are threads of one process (they share one thread pool).
  virtual int ranksOnThisMachine() const { return 1; }

  virtual void barrier() const = 0;
  virtual uint64_t sum(uint64_t value) const = 0;
  virtual double max(double value) const = 0;
  // Element-wise over ranks; every rank passes the same length.
  virtual std::vector<uint64_t> sum(std::span<const uint64_t> values) const = 0;
  virtual std::vector<double> sum(std::span<const double> values) const = 0;
  virtual std::vector<double> max(std::span<const double> values) const = 0;
  // counts[r]: items for rank r; returns how many each rank sends to us.
  virtual std::vector<int> exchangeCounts(const std::vector<int>& sendCounts) const = 0;
  // All-to-all-v of raw bytes; counts and displacements in bytes, one per
  // rank. receiveCounts[r] must equal what rank r sends here.
  virtual void exchangeBytes(const void* send, const std::vector<int>& sendCounts,
                             const std::vector<int>& sendOffsets, void* receive,
                             const std::vector<int>& receiveCounts,
                             const std::vector<int>& receiveOffsets) const = 0;
  // Gathers variable-size byte blocks on rank 0 (receive, counts and offsets
  // are read on rank 0 only).
  virtual void gatherBytes(const void* send, int sendBytes, void* receive,
                           const std::vector<int>& counts,
                           const std::vector<int>& offsets) const = 0;
  virtual std::vector<int> gatherInt(int value) const = 0;  // on rank 0; empty elsewhere
  // Rank 0's bytes to every rank; every rank passes the same length.
  virtual void broadcastBytes(std::span<std::byte> bytes) const = 0;

  // Collective: the ranks that give the same `color` form a communicator of
  // their own, ranked in this one's order (MPI_Comm_split; data groups).
  // Its collectives involve only them; abortAll on it ends every rank.
  virtual std::unique_ptr<Communicator> split(int color) const = 0;

  // Rank 0's values replace every other rank's (e.g. a camera change made on
  // rank 0). Plain data only: the bytes are copied as they are.
  template <typename T>
  void broadcast(std::span<T> values) const {
    static_assert(std::is_trivially_copyable_v<T> && !std::is_const_v<T>);
    broadcastBytes(std::as_writable_bytes(values));
  }
  template <typename T>
  void broadcast(T& value) const {
    broadcast(std::span<T>(&value, 1));
  }

  // --- Non-blocking messages (not collective) ---
  // What the overlapped ray exchange is built on: a rank sends rays to
  // another rank whenever it has them and goes on working; the receiver picks
  // them up when it next looks. Messages from one rank to another arrive in
  // the order they were sent; messages of any size are allowed (the MPI
  // implementation splits what exceeds MPI's int counts). Only the thread
  // that owns the communicator calls these; each call also drives progress.

  // Sends `header` followed by `items` to rank `to` (not this rank) and
  // returns at once; the bytes are copied, so the caller's buffer is free.
  template <typename Header, typename Item>
  SendHandle send(int to, const Header& header, std::span<const Item> items) const {
    static_assert(std::is_trivially_copyable_v<Header> && std::is_trivially_copyable_v<Item>);
    std::vector<std::byte> bytes(sizeof(Header) + items.size_bytes());
    std::memcpy(bytes.data(), &header, sizeof(Header));
    if (!items.empty())
      std::memcpy(bytes.data() + sizeof(Header), items.data(), items.size_bytes());
    return sendBytes(to, std::move(bytes));
  }
  // A message that has arrived for this rank, if any. Every message must
  // have been sent with the same Header and Item types; a message whose size
  // does not fit them throws CommunicationError.
  template <typename Header, typename Item>
  std::optional<Received<Header, Item>> receive() const {
    static_assert(std::is_trivially_copyable_v<Header> && std::is_trivially_copyable_v<Item>);
    std::optional<ReceivedBytes> message = receiveBytes();
    if (!message) return std::nullopt;
    const std::vector<std::byte>& bytes = message->bytes;
    if (bytes.size() < sizeof(Header) || (bytes.size() - sizeof(Header)) % sizeof(Item) != 0)
      throwMalformed(message->from, bytes.size(), sizeof(Header), sizeof(Item));
    Received<Header, Item> out;
    out.from = message->from;
    std::memcpy(&out.header, bytes.data(), sizeof(Header));
    out.items.resize((bytes.size() - sizeof(Header)) / sizeof(Item));
    if (!out.items.empty())
      std::memcpy(out.items.data(), bytes.data() + sizeof(Header), bytes.size() - sizeof(Header));
    return out;
  }
  // send() and receive() in bytes, what an implementation provides (and a
  // wrapper passes on): the message is `bytes`, whatever its size.
  virtual SendHandle sendBytes(int to, std::vector<std::byte> bytes) const = 0;
  virtual std::optional<ReceivedBytes> receiveBytes() const = 0;
  // Whether the send has completed (its bytes handed over; MPI may still be
  // delivering them). Drives progress.
  virtual bool sendDone(SendHandle handle) const = 0;
  // Whether every send this rank started has completed. Drives progress.
  virtual bool allSendsDone() const = 0;
  // Returns when a message may have arrived, or after `timeout`: what a rank
  // with nothing to do calls instead of spinning, so that on an
  // oversubscribed machine it leaves the core to ranks that have work.
  virtual void waitForMessage(std::chrono::microseconds timeout) const = 0;

  // --- Non-blocking sums (collective, but nobody waits in them) ---
  // Starts an element-wise sum over ranks of `values` and returns at once;
  // every rank starts the same sequence of sums with the same lengths, each
  // when it likes. sumDone() answers, without blocking, whether every rank
  // has contributed; then `result` holds the sum. A handle is asked until it
  // is done, and sums complete in the order they were started.
  virtual SumHandle startSum(std::vector<uint64_t> values) const = 0;
  virtual bool sumDone(SumHandle handle, std::vector<uint64_t>& result) const = 0;

  // Collective: true if any rank failed; then rank 0 prints one message (the
  // failing ranks' messages, merged when identical) to stderr.
  bool agreeOnFailure(bool failed, const std::string& message) const;
  // Collective, printing nothing: empty if no rank failed, else the same on
  // every rank: the failing ranks' messages, one line each, merged when
  // identical, "on rank R,S: message" unless every rank failed alike.
  std::string failureMessage(bool failed, const std::string& message) const;
  // Not collective: called by the one rank that failed. Ends every rank with
  // `message` (MPI: prints "ferry: error on rank R: message" and aborts the
  // job with exit code `code`; in-process: throws here and in every other rank).
  [[noreturn]] void abortAll(const std::string& message, int code = 1) const;

 protected:
  // abortAll's work; must not return (end the process or throw).
  virtual void abortEveryRank(const std::string& message, int code) const = 0;

 private:
  [[noreturn]] void throwMalformed(int from, size_t bytes, size_t headerBytes,
                                   size_t itemBytes) const;
};

}  // namespace ferry
