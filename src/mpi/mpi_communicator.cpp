#include "mpi/mpi_communicator.h"

#include <fmt/format.h>
#include <mpi.h>

#include <unistd.h>
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <functional>
#include <list>
#include <string>
#include <thread>

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

// Message tags on the messaging communicator.
constexpr int kWholeMessage = 1;  // a message in one piece
constexpr int kLargeLength = 2;   // the length (uint64_t) of a message that follows in pieces
constexpr int kLargePiece = 3;    // one of those pieces

}  // namespace

struct MpiCommunicator::Messaging {
  MPI_Comm collective = MPI_COMM_NULL;  // the collectives' duplicate of the communicator
  MPI_Comm comm = MPI_COMM_NULL;        // point-to-point messages' duplicate
  struct Send {
    uint64_t id;
    std::vector<std::byte> bytes;
    uint64_t length;  // a large message's length message
    std::vector<MPI_Request> requests;
  };
  // A whole message matched and being received (MPI_Imrecv): a receiver
  // that waited for it in a blocking receive would wait for the sender to
  // make progress, which it does only when it next calls MPI.
  struct Receive {
    int from;
    std::vector<std::byte> bytes;
    MPI_Request request;
    bool done = false;
  };
  std::list<Receive> receives;  // in the order they were matched
  struct Sum {
    uint64_t id;
    std::vector<uint64_t> values, result;
    MPI_Request request;
  };
  std::list<Send> sends;  // in flight; a list, so buffers never move
  std::list<Sum> sums;
  uint64_t nextSend = 1, nextSum = 1;
};

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
  MPI_Comm world = MPI_COMM_WORLD;
  join(&world);
  jobRank_ = rank_;
  countRanksOnMachine();
}

MpiCommunicator::MpiCommunicator(const void* communicator, int jobRank, int ranksOnMachine)
    : jobRank_(jobRank), ranksOnMachine_(ranksOnMachine) {
  join(communicator);
}

std::unique_ptr<Communicator> MpiCommunicator::split(int color) const {
  MPI_Comm part = MPI_COMM_NULL;
  check(MPI_Comm_split(messaging_->collective, color, rank_, &part), "MPI_Comm_split");
  // The job's ranks share the machine, not only the group's.
  std::unique_ptr<Communicator> out(new MpiCommunicator(&part, jobRank_, ranksOnMachine_));
  MPI_Comm_free(&part);  // (it joined duplicates)
  return out;
}

MpiCommunicator::MpiCommunicator(ApplicationCommunicator application) {
  int initialized = 0, finalized = 0;
  check(MPI_Initialized(&initialized), "MPI_Initialized");
  check(MPI_Finalized(&finalized), "MPI_Finalized");
  if (!initialized || finalized)
    throw CommunicationError("MpiCommunicator", -1,
                             "a communicator was given but MPI is not running (MPI_Init first)");
  MPI_Comm comm = MPI_Comm_f2c(MPI_Fint(application.fortranHandle));
  if (comm == MPI_COMM_NULL)
    throw CommunicationError("MpiCommunicator", -1, "the communicator given is MPI_COMM_NULL");
  join(&comm);
  jobRank_ = rank_;
  countRanksOnMachine();
}

void MpiCommunicator::join(const void* communicator) {
  const MPI_Comm comm = *static_cast<const MPI_Comm*>(communicator);
  messaging_ = std::make_unique<Messaging>();
  // Duplicates, so that Ferry's collectives and messages never match the
  // application's; errors come back as codes on them.
  for (MPI_Comm* dup : {&messaging_->collective, &messaging_->comm}) {
    check(MPI_Comm_dup(comm, dup), "MPI_Comm_dup");
    check(MPI_Comm_set_errhandler(*dup, MPI_ERRORS_RETURN), "MPI_Comm_set_errhandler");
  }
  check(MPI_Comm_rank(messaging_->collective, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(messaging_->collective, &size_), "MPI_Comm_size");
}

void MpiCommunicator::countRanksOnMachine() {
  MPI_Comm local = MPI_COMM_NULL;
  check(MPI_Comm_split_type(messaging_->collective, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL,
                            &local),
        "MPI_Comm_split_type");
  const int status = MPI_Comm_size(local, &ranksOnMachine_);
  MPI_Comm_free(&local);
  check(status, "MPI_Comm_size");
}

MpiCommunicator::~MpiCommunicator() {
  if (messaging_)
    for (MPI_Comm* dup : {&messaging_->collective, &messaging_->comm})
      if (*dup != MPI_COMM_NULL) MPI_Comm_free(dup);
  if (ownsMpi_) MPI_Finalize();
}

SendHandle MpiCommunicator::sendBytes(int to, std::vector<std::byte> bytes) const {
  FERRY_CHECK_GE(to, 0);
  FERRY_CHECK_LT(to, size_);
  FERRY_CHECK_NE(to, rank_);
  Messaging& m = *messaging_;
  Messaging::Send& send = m.sends.emplace_back();
  send.id = m.nextSend++;
  send.bytes = std::move(bytes);
  send.length = send.bytes.size();
  auto post = [&](const void* data, size_t count, int tag) {
    MPI_Request request;
    check(MPI_Isend(data, int(count), MPI_BYTE, to, tag, m.comm, &request), "MPI_Isend");
    send.requests.push_back(request);
  };
  const size_t piece = std::max<size_t>(1, maxPieceBytes_);
  if (send.bytes.size() <= piece) {
    post(send.bytes.data(), send.bytes.size(), kWholeMessage);
  } else {
    post(&send.length, sizeof(send.length), kLargeLength);
    for (size_t done = 0; done < send.bytes.size(); done += piece)
      post(send.bytes.data() + done, std::min(piece, send.bytes.size() - done), kLargePiece);
  }
  return SendHandle{send.id};
}

void MpiCommunicator::progressSends() const {
  for (auto it = messaging_->sends.begin(); it != messaging_->sends.end();) {
    int done = 0;
    check(MPI_Testall(int(it->requests.size()), it->requests.data(), &done, MPI_STATUSES_IGNORE),
          "MPI_Testall");
    it = done ? messaging_->sends.erase(it) : std::next(it);
  }
}

bool MpiCommunicator::sendDone(SendHandle handle) const {
  progressSends();
  for (const Messaging::Send& send : messaging_->sends)
    if (send.id == handle.id) return false;
  return true;
}

bool MpiCommunicator::allSendsDone() const {
  progressSends();
  return messaging_->sends.empty();
}

namespace {

// A message above the piece size: its length, then its pieces, received
// here (blocking: they were all posted after the length).
std::vector<std::byte> receiveLarge(MPI_Comm comm, int rank_, const MPI_Status& status,
                                    MPI_Message& message, int count,
                                    const std::function<void(int, const char*)>& check) {
  ReceivedBytes out;
  out.from = status.MPI_SOURCE;
  if (status.MPI_TAG != kLargeLength || count != int(sizeof(uint64_t)))
    throw CommunicationError("MPI_Improbe", rank_,
                             fmt::format("unexpected message (tag {}, {} bytes) from rank {}",
                                         status.MPI_TAG, count, out.from));
  uint64_t length = 0;
  check(MPI_Mrecv(&length, count, MPI_BYTE, &message, MPI_STATUS_IGNORE), "MPI_Mrecv");
  out.bytes.resize(length);
  // The pieces were all posted after the length, in order (MPI does not
  // let messages from one sender overtake each other): receive them now.
  for (size_t done = 0; done < length;) {
    MPI_Status piece;
    check(MPI_Probe(out.from, kLargePiece, comm, &piece), "MPI_Probe");
    int pieceBytes = 0;
    check(MPI_Get_count(&piece, MPI_BYTE, &pieceBytes), "MPI_Get_count");
    if (pieceBytes <= 0 || done + size_t(pieceBytes) > length)
      throw CommunicationError(
          "MPI_Recv", rank_,
          fmt::format("a piece of {} bytes overruns a {}-byte message", pieceBytes, length));
    check(MPI_Recv(out.bytes.data() + done, pieceBytes, MPI_BYTE, out.from, kLargePiece, comm,
                   MPI_STATUS_IGNORE),
          "MPI_Recv");
    done += size_t(pieceBytes);
  }
  return std::move(out.bytes);
}

}  // namespace

std::optional<ReceivedBytes> MpiCommunicator::receiveBytes() const {
  progressSends();
  Messaging& m = *messaging_;
  // Match every message that has arrived and start receiving it.
  for (;;) {
    int found = 0;
    MPI_Message message;
    MPI_Status status;
    check(MPI_Improbe(MPI_ANY_SOURCE, MPI_ANY_TAG, m.comm, &found, &message, &status),
          "MPI_Improbe");
    if (!found) break;
    int count = 0;
    check(MPI_Get_count(&status, MPI_BYTE, &count), "MPI_Get_count");
    if (status.MPI_TAG == kWholeMessage) {
      Messaging::Receive& r = m.receives.emplace_back();
      r.from = status.MPI_SOURCE;
      r.bytes.resize(size_t(count));
      check(MPI_Imrecv(r.bytes.data(), count, MPI_BYTE, &message, &r.request), "MPI_Imrecv");
      continue;
    }
    // A message in pieces (above 1 GiB): received whole, here (it queues
    // after the earlier messages of its sender).
    Messaging::Receive& r = m.receives.emplace_back();
    r.from = status.MPI_SOURCE;
    r.bytes = receiveLarge(m.comm, rank_, status, message, count,
                           [this](int code, const char* operation) { check(code, operation); });
    r.request = MPI_REQUEST_NULL;
    r.done = true;
  }
  // The first complete message whose sender has no earlier one still coming
  // (messages from one rank arrive in the order sent).
  for (auto it = m.receives.begin(); it != m.receives.end(); ++it) {
    if (!it->done) {
      int done = 0;
      check(MPI_Test(&it->request, &done, MPI_STATUS_IGNORE), "MPI_Test");
      it->done = done != 0;
    }
    bool earlier = false;
    for (auto e = m.receives.begin(); e != it && !earlier; ++e) earlier = e->from == it->from;
    if (!it->done || earlier) continue;
    ReceivedBytes out{it->from, std::move(it->bytes)};
    m.receives.erase(it);
    return out;
  }
  return std::nullopt;
}

void MpiCommunicator::waitForMessage(std::chrono::microseconds timeout) const {
  // MPI has no wait-with-timeout: look once, else give the core away for the
  // timeout (a rank that spins in MPI steals it from ranks that have work
  // when ranks outnumber cores).
  progressSends();
  int found = 0;
  check(MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, messaging_->comm, &found, MPI_STATUS_IGNORE),
        "MPI_Iprobe");
  if (!found) std::this_thread::sleep_for(timeout);
}

SumHandle MpiCommunicator::startSum(std::vector<uint64_t> values) const {
  Messaging& m = *messaging_;
  Messaging::Sum& sum = m.sums.emplace_back();
  sum.id = m.nextSum++;
  sum.values = std::move(values);
  sum.result.resize(sum.values.size());
  check(MPI_Iallreduce(sum.values.data(), sum.result.data(), int(sum.values.size()), MPI_UINT64_T,
                       MPI_SUM, m.comm, &sum.request),
        "MPI_Iallreduce");
  return SumHandle{sum.id};
}

bool MpiCommunicator::sumDone(SumHandle handle, std::vector<uint64_t>& result) const {
  progressSends();
  for (auto it = messaging_->sums.begin(); it != messaging_->sums.end(); ++it) {
    if (it->id != handle.id) continue;
    int done = 0;
    check(MPI_Test(&it->request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (!done) return false;
    result = std::move(it->result);
    messaging_->sums.erase(it);
    return true;
  }
  throw CommunicationError("sumDone", rank_, "no such sum (asked again after it was done?)");
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
  check(MPI_Barrier(messaging_->collective), "MPI_Barrier");
}

uint64_t MpiCommunicator::sum(uint64_t value) const {
  uint64_t out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_UINT64_T, MPI_SUM, messaging_->collective),
        "MPI_Allreduce");
  return out;
}

double MpiCommunicator::max(double value) const {
  double out = 0;
  check(MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, messaging_->collective),
        "MPI_Allreduce");
  return out;
}

std::vector<uint64_t> MpiCommunicator::sum(std::span<const uint64_t> values) const {
  std::vector<uint64_t> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_UINT64_T, MPI_SUM,
                      messaging_->collective),
        "MPI_Allreduce");
  return out;
}

std::vector<double> MpiCommunicator::sum(std::span<const double> values) const {
  std::vector<double> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_DOUBLE, MPI_SUM,
                      messaging_->collective),
        "MPI_Allreduce");
  return out;
}

std::vector<double> MpiCommunicator::max(std::span<const double> values) const {
  std::vector<double> out(values.size());
  check(MPI_Allreduce(values.data(), out.data(), int(values.size()), MPI_DOUBLE, MPI_MAX,
                      messaging_->collective),
        "MPI_Allreduce");
  return out;
}

std::vector<int> MpiCommunicator::exchangeCounts(const std::vector<int>& sendCounts) const {
  FERRY_CHECK_EQ(sendCounts.size(), size_);
  std::vector<int> receive(size_);
  check(MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receive.data(), 1, MPI_INT,
                     messaging_->collective),
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
  check(
      MPI_Alltoallv(send, sendCounts.data(), sendOffsets.data(), MPI_BYTE, receive,
                    receiveCounts.data(), receiveOffsets.data(), MPI_BYTE, messaging_->collective),
      "MPI_Alltoallv");
}

void MpiCommunicator::gatherBytes(const void* send, int sendBytes, void* receive,
                                  const std::vector<int>& counts,
                                  const std::vector<int>& offsets) const {
  check(MPI_Gatherv(send, sendBytes, MPI_BYTE, receive, counts.data(), offsets.data(), MPI_BYTE, 0,
                    messaging_->collective),
        "MPI_Gatherv");
}

std::vector<int> MpiCommunicator::gatherInt(int value) const {
  std::vector<int> out(isRoot() ? size_ : 0);
  check(MPI_Gather(&value, 1, MPI_INT, out.data(), 1, MPI_INT, 0, messaging_->collective),
        "MPI_Gather");
  return out;
}

void MpiCommunicator::broadcastBytes(std::span<std::byte> bytes) const {
  // MPI counts are ints: large buffers go in pieces of at most 1 GiB.
  constexpr size_t kPiece = size_t(1) << 30;
  for (size_t done = 0; done < bytes.size(); done += kPiece) {
    size_t piece = std::min(kPiece, bytes.size() - done);
    check(MPI_Bcast(bytes.data() + done, int(piece), MPI_BYTE, 0, messaging_->collective),
          "MPI_Bcast");
  }
}

void MpiCommunicator::reportFatalSignals() const {
  std::snprintf(gSignalMessage, sizeof(gSignalMessage), "ferry: rank %d died of ", rank_);
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(s, onFatalSignal);
}

void MpiCommunicator::abortEveryRank(const std::string& message, int code) const {
  fmt::print(stderr, "ferry: error on rank {}: {}\n", jobRank_, message);
  std::fflush(stderr);
  MPI_Abort(messaging_ ? messaging_->collective : messaging_->collective, code);
  std::_Exit(code);  // MPI_Abort does not return; be sure
}

}  // namespace ferry
