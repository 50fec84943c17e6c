#include "comm/in_process_communicator.h"

#include <fmt/format.h>

#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <map>
#include <mutex>
#include <string_view>
#include <thread>
#include <utility>

#include "core/error.h"

namespace ferry {

// Every collective is two rounds of a reusable barrier (generation-counted)
// around the reads: deposit, wait for all, read the others' deposits, wait
// for all again.
struct InProcessHub {
  explicit InProcessHub(int n)
      : size(n), operations(n), deposits(n), inboxes(n), sumsStarted(n, 0) {}

  const int size;
  std::mutex mutex;
  std::condition_variable changed;
  // Per rank, while it is inside a collective: which one, and a pointer to its
  // contribution (the caller's memory, valid until the collective returns).
  std::vector<const char*> operations;
  std::vector<const void*> deposits;
  int arrived = 0;          // ranks waiting at the current barrier
  uint64_t generation = 0;  // barriers completed
  int leftRank = -1;        // the first rank whose work returned
  int abortingRank = -1;    // the first rank that aborted
  std::string abortMessage;

  // Non-blocking messages: each rank's arrived messages, oldest first.
  std::vector<std::deque<ReceivedBytes>> inboxes;
  // Non-blocking sums, by sequence number: the running sum, how many ranks
  // have contributed and how many have read the result (then it goes).
  struct PendingSum {
    std::vector<uint64_t> total;
    int contributed = 0, read = 0;
  };
  std::map<uint64_t, PendingSum> sums;
  std::vector<uint64_t> sumsStarted;  // per rank

  // split(): the groups made, by (the split's number, colour); each rank
  // counts its splits, so the k-th split is the same on every rank. A group
  // knows its parent, so that an abort anywhere reaches every rank.
  InProcessHub* parent = nullptr;
  std::map<std::pair<uint64_t, int>, std::shared_ptr<InProcessHub>> children;
  std::vector<uint64_t> splitsStarted = std::vector<uint64_t>(size_t(size), 0);
};

namespace {

// Throws if the group can no longer complete a collective.
void throwIfBroken(const InProcessHub& hub, int rank, const char* operation) {
  if (hub.abortingRank >= 0)
    throw GroupAborted(operation, rank, hub.abortingRank, hub.abortMessage);
  if (hub.leftRank >= 0)
    throw CommunicationError(
        operation, rank,
        fmt::format("rank {} finished its work, so this collective can never complete (the "
                    "ranks' collectives do not match)",
                    hub.leftRank));
}

// Waits until every rank has arrived (the lock held on entry and return).
// With `stopWhenBroken`, throws instead once the group can never complete.
void waitForAll(InProcessHub& hub, std::unique_lock<std::mutex>& lock, int rank,
                const char* operation, bool stopWhenBroken) {
  if (stopWhenBroken) throwIfBroken(hub, rank, operation);
  const uint64_t generation = hub.generation;
  if (++hub.arrived == hub.size) {
    hub.arrived = 0;
    ++hub.generation;
    hub.changed.notify_all();
    return;
  }
  hub.changed.wait(lock, [&] {
    return hub.generation != generation ||
           (stopWhenBroken && (hub.abortingRank >= 0 || hub.leftRank >= 0));
  });
  if (hub.generation != generation) return;
  throwIfBroken(hub, rank, operation);
}

// One collective: `contribution` is this rank's input; read(contributions)
// computes this rank's result from every rank's, indexed by rank.
template <typename Read>
void collective(InProcessHub& hub, int rank, const char* operation, const void* contribution,
                const Read& read) {
  std::unique_lock lock(hub.mutex);
  hub.operations[rank] = operation;
  hub.deposits[rank] = contribution;
  waitForAll(hub, lock, rank, operation, true);
  // Stable until the second barrier: a rank writes its entries only when it
  // enters its next collective.
  const std::vector<const char*> operations = hub.operations;
  const std::vector<const void*> deposits = hub.deposits;
  lock.unlock();
  std::exception_ptr error;
  try {
    for (int r = 0; r < hub.size; ++r)
      if (std::string_view(operations[r]) != operation)
        throw CommunicationError(operation, rank,
                                 fmt::format("rank {} called {} at the same point (the ranks' "
                                             "collectives do not match)",
                                             r, operations[r]));
    read(deposits);
  } catch (...) {
    error = std::current_exception();
  }
  lock.lock();
  // No buffer goes away before every rank has read it. Every rank is inside
  // this collective now (and so cannot abort), so this wait always completes.
  waitForAll(hub, lock, rank, operation, false);
  if (error) std::rethrow_exception(error);
}

template <typename T>
std::vector<T> reduce(InProcessHub& hub, int rank, const char* operation, std::span<const T> values,
                      T (*combine)(T, T)) {
  std::vector<T> out(values.begin(), values.end());
  collective(hub, rank, operation, &values, [&](const std::vector<const void*>& all) {
    for (int r = 0; r < hub.size; ++r) {
      const auto& theirs = *static_cast<const std::span<const T>*>(all[r]);
      if (theirs.size() != values.size())
        throw CommunicationError(
            operation, rank,
            fmt::format("rank {} passes {} values, this rank {}", r, theirs.size(), values.size()));
    }
    // In rank order, starting from rank 0's values, on every rank alike.
    const auto& first = *static_cast<const std::span<const T>*>(all[0]);
    std::copy(first.begin(), first.end(), out.begin());
    for (int r = 1; r < hub.size; ++r) {
      const auto& theirs = *static_cast<const std::span<const T>*>(all[r]);
      for (size_t i = 0; i < out.size(); ++i) out[i] = combine(out[i], theirs[i]);
    }
  });
  return out;
}

template <typename T>
T add(T a, T b) {
  return a + b;
}
double larger(double a, double b) {
  return std::max(a, b);
}

// What a rank brings to exchangeBytes: the others read their parts of it.
struct ExchangeSend {
  const std::byte* data;
  const std::vector<int>* counts;
  const std::vector<int>* offsets;
};

struct GatherSend {
  const std::byte* data;
  int bytes;
};

}  // namespace

GroupAborted::GroupAborted(std::string operation, int rank, int abortingRank,
                           const std::string& reason)
    : CommunicationError(std::move(operation), rank,
                         fmt::format("rank {} aborted: {}", abortingRank, reason)),
      abortingRank_(abortingRank),
      reason_(reason) {}

int InProcessCommunicator::size() const {
  return hub_.size;
}

void InProcessCommunicator::barrier() const {
  collective(hub_, rank_, "barrier", nullptr, [](const std::vector<const void*>&) {});
}

uint64_t InProcessCommunicator::sum(uint64_t value) const {
  return reduce<uint64_t>(hub_, rank_, "sum(uint64_t)", std::span(&value, 1), add)[0];
}

double InProcessCommunicator::max(double value) const {
  return reduce<double>(hub_, rank_, "max(double)", std::span(&value, 1), larger)[0];
}

std::vector<uint64_t> InProcessCommunicator::sum(std::span<const uint64_t> values) const {
  return reduce<uint64_t>(hub_, rank_, "sum(span<uint64_t>)", values, add);
}

std::vector<double> InProcessCommunicator::sum(std::span<const double> values) const {
  return reduce<double>(hub_, rank_, "sum(span<double>)", values, add);
}

std::vector<double> InProcessCommunicator::max(std::span<const double> values) const {
  return reduce<double>(hub_, rank_, "max(span<double>)", values, larger);
}

std::vector<int> InProcessCommunicator::exchangeCounts(const std::vector<int>& sendCounts) const {
  FERRY_CHECK_EQ(sendCounts.size(), hub_.size);
  std::vector<int> receive(hub_.size);
  collective(hub_, rank_, "exchangeCounts", &sendCounts, [&](const std::vector<const void*>& all) {
    for (int r = 0; r < hub_.size; ++r)
      receive[r] = (*static_cast<const std::vector<int>*>(all[r]))[rank_];
  });
  return receive;
}

void InProcessCommunicator::exchangeBytes(const void* send, const std::vector<int>& sendCounts,
                                          const std::vector<int>& sendOffsets, void* receive,
                                          const std::vector<int>& receiveCounts,
                                          const std::vector<int>& receiveOffsets) const {
  const int n = hub_.size;
  FERRY_CHECK_EQ(sendCounts.size(), n);
  FERRY_CHECK_EQ(sendOffsets.size(), n);
  FERRY_CHECK_EQ(receiveCounts.size(), n);
  FERRY_CHECK_EQ(receiveOffsets.size(), n);
  const ExchangeSend mine{static_cast<const std::byte*>(send), &sendCounts, &sendOffsets};
  collective(hub_, rank_, "exchangeBytes", &mine, [&](const std::vector<const void*>& all) {
    for (int r = 0; r < n; ++r) {
      const auto& theirs = *static_cast<const ExchangeSend*>(all[r]);
      const int bytes = (*theirs.counts)[rank_];
      if (bytes != receiveCounts[r])
        throw CommunicationError("exchangeBytes", rank_,
                                 fmt::format("rank {} sends {} bytes, this rank expects {}", r,
                                             bytes, receiveCounts[r]));
      if (bytes > 0)
        std::memcpy(static_cast<std::byte*>(receive) + receiveOffsets[r],
                    theirs.data + (*theirs.offsets)[rank_], size_t(bytes));
    }
  });
}

void InProcessCommunicator::gatherBytes(const void* send, int sendBytes, void* receive,
                                        const std::vector<int>& counts,
                                        const std::vector<int>& offsets) const {
  const GatherSend mine{static_cast<const std::byte*>(send), sendBytes};
  collective(hub_, rank_, "gatherBytes", &mine, [&](const std::vector<const void*>& all) {
    if (!isRoot()) return;
    FERRY_CHECK_EQ(counts.size(), hub_.size);
    FERRY_CHECK_EQ(offsets.size(), hub_.size);
    for (int r = 0; r < hub_.size; ++r) {
      const auto& theirs = *static_cast<const GatherSend*>(all[r]);
      if (theirs.bytes != counts[r])
        throw CommunicationError(
            "gatherBytes", rank_,
            fmt::format("rank {} sends {} bytes, rank 0 expects {}", r, theirs.bytes, counts[r]));
      if (theirs.bytes > 0)
        std::memcpy(static_cast<std::byte*>(receive) + offsets[r], theirs.data,
                    size_t(theirs.bytes));
    }
  });
}

std::vector<int> InProcessCommunicator::gatherInt(int value) const {
  std::vector<int> out(isRoot() ? hub_.size : 0);
  collective(hub_, rank_, "gatherInt", &value, [&](const std::vector<const void*>& all) {
    for (size_t r = 0; r < out.size(); ++r) out[r] = *static_cast<const int*>(all[r]);
  });
  return out;
}

void InProcessCommunicator::broadcastBytes(std::span<std::byte> bytes) const {
  collective(hub_, rank_, "broadcastBytes", &bytes, [&](const std::vector<const void*>& all) {
    const auto& root = *static_cast<const std::span<std::byte>*>(all[0]);
    if (root.size() != bytes.size())
      throw CommunicationError(
          "broadcastBytes", rank_,
          fmt::format("rank 0 sends {} bytes, this rank expects {}", root.size(), bytes.size()));
    if (!isRoot() && !bytes.empty()) std::memcpy(bytes.data(), root.data(), bytes.size());
  });
}

SendHandle InProcessCommunicator::sendBytes(int to, std::vector<std::byte> bytes) const {
  FERRY_CHECK_GE(to, 0);
  FERRY_CHECK_LT(to, hub_.size);
  FERRY_CHECK_NE(to, rank_);
  std::unique_lock lock(hub_.mutex);
  if (hub_.abortingRank >= 0)
    throw GroupAborted("send", rank_, hub_.abortingRank, hub_.abortMessage);
  hub_.inboxes[size_t(to)].push_back(ReceivedBytes{rank_, std::move(bytes)});
  hub_.changed.notify_all();
  return SendHandle{0};  // delivered: complete at once
}

std::optional<ReceivedBytes> InProcessCommunicator::receiveBytes() const {
  std::unique_lock lock(hub_.mutex);
  if (hub_.abortingRank >= 0)
    throw GroupAborted("receive", rank_, hub_.abortingRank, hub_.abortMessage);
  std::deque<ReceivedBytes>& inbox = hub_.inboxes[size_t(rank_)];
  if (inbox.empty()) return std::nullopt;
  ReceivedBytes message = std::move(inbox.front());
  inbox.pop_front();
  return message;
}

bool InProcessCommunicator::sendDone(SendHandle) const {
  return true;
}

bool InProcessCommunicator::allSendsDone() const {
  return true;
}

void InProcessCommunicator::waitForMessage(std::chrono::microseconds timeout) const {
  std::unique_lock lock(hub_.mutex);
  hub_.changed.wait_for(lock, timeout, [&] {
    return hub_.abortingRank >= 0 || !hub_.inboxes[size_t(rank_)].empty();
  });
  if (hub_.abortingRank >= 0)
    throw GroupAborted("waitForMessage", rank_, hub_.abortingRank, hub_.abortMessage);
}

SumHandle InProcessCommunicator::startSum(std::vector<uint64_t> values) const {
  std::unique_lock lock(hub_.mutex);
  if (hub_.abortingRank >= 0)
    throw GroupAborted("startSum", rank_, hub_.abortingRank, hub_.abortMessage);
  const uint64_t id = hub_.sumsStarted[size_t(rank_)]++;
  InProcessHub::PendingSum& pending = hub_.sums[id];
  if (pending.contributed == 0) {
    pending.total = std::move(values);
  } else {
    if (pending.total.size() != values.size())
      throw CommunicationError("startSum", rank_,
                               fmt::format("this rank sums {} values, another rank {}",
                                           values.size(), pending.total.size()));
    for (size_t i = 0; i < values.size(); ++i) pending.total[i] += values[i];
  }
  ++pending.contributed;
  hub_.changed.notify_all();
  return SumHandle{id};
}

bool InProcessCommunicator::sumDone(SumHandle handle, std::vector<uint64_t>& result) const {
  std::unique_lock lock(hub_.mutex);
  if (hub_.abortingRank >= 0)
    throw GroupAborted("sumDone", rank_, hub_.abortingRank, hub_.abortMessage);
  auto it = hub_.sums.find(handle.id);
  FERRY_CHECK(it != hub_.sums.end());
  InProcessHub::PendingSum& pending = it->second;
  if (pending.contributed < hub_.size) {
    if (hub_.leftRank >= 0)
      throw CommunicationError(
          "sumDone", rank_,
          fmt::format("rank {} finished its work, so this sum can never complete", hub_.leftRank));
    return false;
  }
  result = pending.total;
  if (++pending.read == hub_.size) hub_.sums.erase(it);
  return true;
}

namespace {

// Marks `hub` and every group split from it aborted (the first abort is the
// one reported) and wakes their ranks.
void abortFrom(InProcessHub& hub, int rank, const std::string& message) {
  std::vector<InProcessHub*> children;
  {
    std::unique_lock lock(hub.mutex);
    if (hub.abortingRank < 0) {
      hub.abortingRank = rank;
      hub.abortMessage = message;
    }
    hub.changed.notify_all();
    for (auto& [key, child] : hub.children) children.push_back(child.get());
  }
  for (InProcessHub* child : children) abortFrom(*child, rank, message);
}

// An abort anywhere ends every rank of the run, as MPI_Abort ends the job.
void abortRun(InProcessHub& hub, int rank, const std::string& message) {
  InProcessHub* root = &hub;
  while (root->parent) root = root->parent;
  abortFrom(*root, rank, message);
}

}  // namespace

std::unique_ptr<Communicator> InProcessCommunicator::split(int color) const {
  std::vector<int> colors = gatherInt(color);
  colors.resize(size_t(hub_.size));
  broadcast(std::span<int>(colors));
  int rank = 0, size = 0;
  for (int r = 0; r < hub_.size; ++r)
    if (colors[size_t(r)] == color) {
      if (r < rank_) ++rank;
      ++size;
    }
  std::unique_lock lock(hub_.mutex);
  const uint64_t number = hub_.splitsStarted[size_t(rank_)]++;
  std::shared_ptr<InProcessHub>& child = hub_.children[{number, color}];
  if (!child) {
    child = std::make_shared<InProcessHub>(size);
    child->parent = &hub_;
  }
  return std::unique_ptr<Communicator>(new InProcessCommunicator(*child, rank));
}

void InProcessCommunicator::abortEveryRank(const std::string& message, int) const {
  abortRun(hub_, rank_, message);
  std::unique_lock lock(hub_.mutex);
  throw GroupAborted("abortAll", rank_, hub_.abortingRank, hub_.abortMessage);
}

InProcessGroup::InProcessGroup(int size) : hub_(std::make_unique<InProcessHub>(size)) {
  FERRY_CHECK_GE(size, 1);
  for (int r = 0; r < size; ++r)
    communicators_.push_back(
        std::unique_ptr<InProcessCommunicator>(new InProcessCommunicator(*hub_, r)));
}

InProcessGroup::~InProcessGroup() = default;

int InProcessGroup::size() const {
  return hub_->size;
}

const Communicator& InProcessGroup::communicator(int rank) const {
  FERRY_CHECK_GE(rank, 0);
  FERRY_CHECK_LT(rank, hub_->size);
  return *communicators_[rank];
}

void InProcessGroup::leave(int rank) {
  std::unique_lock lock(hub_->mutex);
  if (hub_->leftRank < 0) hub_->leftRank = rank;
  hub_->changed.notify_all();
}

void InProcessGroup::abort(int rank, const std::string& message) {
  abortFrom(*hub_, rank, message);
}

int InProcessGroup::abortingRank() const {
  std::unique_lock lock(hub_->mutex);
  return hub_->abortingRank;
}

void runRanks(int ranks, const std::function<void(const Communicator&)>& body) {
  InProcessGroup group(ranks);
  std::vector<std::exception_ptr> errors(ranks);
  auto runRank = [&](int r) {
    try {
      body(group.communicator(r));
      group.leave(r);
    } catch (const std::exception& e) {
      errors[r] = std::current_exception();
      group.abort(r, e.what());
    } catch (...) {
      errors[r] = std::current_exception();
      group.abort(r, "unknown exception");
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(ranks);
  try {
    for (int r = 0; r < ranks; ++r) threads.emplace_back(runRank, r);
  } catch (...) {  // could not start a thread: end the ranks already running
    group.abort(int(threads.size()), "could not start the rank's thread");
    for (std::thread& t : threads) t.join();
    throw;
  }
  for (std::thread& t : threads) t.join();
  const int first = group.abortingRank();
  if (first >= 0 && errors[first]) std::rethrow_exception(errors[first]);
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace ferry
