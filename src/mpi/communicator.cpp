#include "mpi/communicator.h"

#include <fmt/format.h>
#include <mpi.h>

#include <unistd.h>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace ferry {
namespace {

// Written by the signal handler with write(2): no allocation there.
char gSignalMessage[128];

void onFatalSignal(int signal) {
  const char* name = signal == SIGSEGV   ? "SIGSEGV"
                     : signal == SIGBUS  ? "SIGBUS"
                     : signal == SIGFPE  ? "SIGFPE"
                     : signal == SIGILL  ? "SIGILL"
                     : signal == SIGABRT ? "SIGABRT"
                                         : "a signal";
  ssize_t ignored = write(STDERR_FILENO, gSignalMessage, strlen(gSignalMessage));
  ignored = write(STDERR_FILENO, name, strlen(name));
  ignored = write(STDERR_FILENO, "\n", 1);
  (void)ignored;
  std::signal(signal, SIG_DFL);
  std::raise(signal);
}

void check(int code, const char* what) {
  if (code != MPI_SUCCESS)
    throw std::runtime_error(fmt::format("MPI failed in {} (code {})", what, code));
}

}  // namespace

Communicator::Communicator(int* argc, char*** argv) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) {
    int provided = 0;
    check(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    ownsMpi_ = true;
  }
  // Errors come back as codes (and exceptions here) rather than killing the job silently.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

Communicator::~Communicator() {
  if (ownsMpi_) MPI_Finalize();
}

void Communicator::barrier() const {
  check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
}

uint64_t Communicator::sum(uint64_t value) const {
  uint64_t out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
  return out;
}

double Communicator::max(double value) const {
  double out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  return out;
}

std::vector<uint64_t> Communicator::sum(std::span<const uint64_t> values) const {
  std::vector<uint64_t> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_UINT64_T, MPI_SUM,
                      MPI_COMM_WORLD),
        "MPI_Allreduce");
  return out;
}

std::vector<double> Communicator::sum(std::span<const double> values) const {
  std::vector<double> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_DOUBLE, MPI_SUM,
                      MPI_COMM_WORLD),
        "MPI_Allreduce");
  return out;
}

std::vector<double> Communicator::max(std::span<const double> values) const {
  std::vector<double> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_DOUBLE, MPI_MAX,
                      MPI_COMM_WORLD),
        "MPI_Allreduce");
  return out;
}

std::vector<int> Communicator::exchangeCounts(const std::vector<int>& sendCounts) const {
  std::vector<int> receive(size_);
  check(MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receive.data(), 1, MPI_INT, MPI_COMM_WORLD),
        "MPI_Alltoall");
  return receive;
}

void Communicator::exchangeBytes(const void* send, const std::vector<int>& sendCounts,
                                 const std::vector<int>& sendOffsets, void* receive,
                                 const std::vector<int>& receiveCounts,
                                 const std::vector<int>& receiveOffsets) const {
  check(MPI_Alltoallv(send, sendCounts.data(), sendOffsets.data(), MPI_BYTE, receive,
                      receiveCounts.data(), receiveOffsets.data(), MPI_BYTE, MPI_COMM_WORLD),
        "MPI_Alltoallv");
}

void Communicator::gatherBytes(const void* send, int sendBytes, void* receive,
                               const std::vector<int>& counts,
                               const std::vector<int>& offsets) const {
  check(MPI_Gatherv(send, sendBytes, MPI_BYTE, receive, counts.data(), offsets.data(), MPI_BYTE, 0,
                    MPI_COMM_WORLD),
        "MPI_Gatherv");
}

std::vector<int> Communicator::gatherInt(int value) const {
  std::vector<int> out(isRoot() ? size_ : 0);
  check(MPI_Gather(&value, 1, MPI_INT, out.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  return out;
}

bool Communicator::agreeOnFailure(bool failed, const std::string& message) const {
  int local = failed ? 1 : 0, any = 0;
  check(MPI_Allreduce(&local, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  if (!any) return false;
  // Gather every rank's message on rank 0 and print it once.
  std::string mine = failed ? message : std::string();
  std::vector<int> lengths = gatherInt(int(mine.size()));
  std::vector<int> offsets(lengths.size(), 0);
  std::string all;
  if (isRoot()) {
    int total = 0;
    for (size_t r = 0; r < lengths.size(); ++r) {
      offsets[r] = total;
      total += lengths[r];
    }
    all.resize(total);
  }
  gatherBytes(mine.data(), int(mine.size()), all.data(), lengths, offsets);
  if (isRoot()) {
    std::vector<std::pair<std::string, std::vector<int>>> distinct;
    for (int r = 0; r < size_; ++r) {
      if (lengths[r] == 0) continue;
      std::string m = all.substr(offsets[r], lengths[r]);
      auto it = std::find_if(distinct.begin(), distinct.end(),
                             [&](const auto& d) { return d.first == m; });
      if (it == distinct.end())
        distinct.push_back({m, {r}});
      else
        it->second.push_back(r);
    }
    for (const auto& [m, ranks] : distinct) {
      if (int(ranks.size()) == size_ || size_ == 1) {
        fmt::print(stderr, "ferry: error: {}\n", m);
      } else {
        std::string list;
        for (int r : ranks) {
          if (!list.empty()) list += ',';
          list += std::to_string(r);
        }
        fmt::print(stderr, "ferry: error on rank {}: {}\n", list, m);
      }
    }
    std::fflush(stderr);
  }
  return true;
}

void Communicator::reportFatalSignals() const {
  std::snprintf(gSignalMessage, sizeof(gSignalMessage), "ferry: rank %d died of ", rank_);
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(s, onFatalSignal);
}

void Communicator::abortAll(const std::string& message, int code) const {
  fmt::print(stderr, "ferry: error on rank {}: {}\n", rank_, message);
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);  // MPI_Abort does not return; be sure
}

}  // namespace ferry
