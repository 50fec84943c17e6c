#include "mpi/mpi_communicator.h"

#include <fmt/format.h>
#include <mpi.h>

#include <unistd.h>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <string>

#include "core/error.h"

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

}  // namespace

MpiCommunicator::MpiCommunicator(int* argc, char*** argv) {
  int initialized = 0;
  check(MPI_Initialized(&initialized), "MPI_Initialized");
  if (!initialized) {
    int provided = 0;
    check(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
    ownsMpi_ = true;
  }
  // Errors come back as codes (and exceptions here) rather than killing the job silently.
  check(MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN), "MPI_Comm_set_errhandler");
  check(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(MPI_COMM_WORLD, &size_), "MPI_Comm_size");
}

MpiCommunicator::~MpiCommunicator() {
  if (ownsMpi_) MPI_Finalize();
}

void MpiCommunicator::check(int code, const char* operation) const {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  if (MPI_Error_string(code, text, &length) != MPI_SUCCESS) length = 0;
  throw CommunicationError(operation, rank_,
                           fmt::format("{} (MPI error code {})",
                                       length > 0 ? std::string(text, length) : "MPI error", code));
}

void MpiCommunicator::barrier() const {
  check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier");
}

uint64_t MpiCommunicator::sum(uint64_t value) const {
  uint64_t out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce");
  return out;
}

double MpiCommunicator::max(double value) const {
  double out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  return out;
}

std::vector<uint64_t> MpiCommunicator::sum(std::span<const uint64_t> values) const {
  std::vector<uint64_t> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_UINT64_T, MPI_SUM,
                      MPI_COMM_WORLD),
        "MPI_Allreduce");
  return out;
}

std::vector<double> MpiCommunicator::sum(std::span<const double> values) const {
  std::vector<double> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_DOUBLE, MPI_SUM,
                      MPI_COMM_WORLD),
        "MPI_Allreduce");
  return out;
}

std::vector<double> MpiCommunicator::max(std::span<const double> values) const {
  std::vector<double> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_DOUBLE, MPI_MAX,
                      MPI_COMM_WORLD),
        "MPI_Allreduce");
  return out;
}

std::vector<int> MpiCommunicator::exchangeCounts(const std::vector<int>& sendCounts) const {
  FERRY_CHECK_EQ(sendCounts.size(), size_);
  std::vector<int> receive(size_);
  check(MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receive.data(), 1, MPI_INT, MPI_COMM_WORLD),
        "MPI_Alltoall");
  return receive;
}

void MpiCommunicator::exchangeBytes(const void* send, const std::vector<int>& sendCounts,
                                    const std::vector<int>& sendOffsets, void* receive,
                                    const std::vector<int>& receiveCounts,
                                    const std::vector<int>& receiveOffsets) const {
  FERRY_CHECK_EQ(sendCounts.size(), size_);
  FERRY_CHECK_EQ(sendOffsets.size(), size_);
  FERRY_CHECK_EQ(receiveCounts.size(), size_);
  FERRY_CHECK_EQ(receiveOffsets.size(), size_);
  check(MPI_Alltoallv(send, sendCounts.data(), sendOffsets.data(), MPI_BYTE, receive,
                      receiveCounts.data(), receiveOffsets.data(), MPI_BYTE, MPI_COMM_WORLD),
        "MPI_Alltoallv");
}

void MpiCommunicator::gatherBytes(const void* send, int sendBytes, void* receive,
                                  const std::vector<int>& counts,
                                  const std::vector<int>& offsets) const {
  check(MPI_Gatherv(send, sendBytes, MPI_BYTE, receive, counts.data(), offsets.data(), MPI_BYTE, 0,
                    MPI_COMM_WORLD),
        "MPI_Gatherv");
}

std::vector<int> MpiCommunicator::gatherInt(int value) const {
  std::vector<int> out(isRoot() ? size_ : 0);
  check(MPI_Gather(&value, 1, MPI_INT, out.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  return out;
}

void MpiCommunicator::broadcastBytes(std::span<std::byte> bytes) const {
  // MPI counts are ints: large buffers go in pieces of at most 1 GiB.
  constexpr size_t kPiece = size_t(1) << 30;
  for (size_t done = 0; done < bytes.size(); done += kPiece) {
    size_t piece = std::min(kPiece, bytes.size() - done);
    check(MPI_Bcast(bytes.data() + done, int(piece), MPI_BYTE, 0, MPI_COMM_WORLD), "MPI_Bcast");
  }
}

void MpiCommunicator::reportFatalSignals() const {
  std::snprintf(gSignalMessage, sizeof(gSignalMessage), "ferry: rank %d died of ", rank_);
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(s, onFatalSignal);
}

void MpiCommunicator::abortEveryRank(const std::string& message, int code) const {
  fmt::print(stderr, "ferry: error on rank {}: {}\n", rank_, message);
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);  // MPI_Abort does not return; be sure
}

}  // namespace ferry
