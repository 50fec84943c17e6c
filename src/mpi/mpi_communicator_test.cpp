#include "mpi/mpi_communicator.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "comm/communicator_test_util.h"

namespace ferry {
namespace {

// One test only: MPI starts once per process and cannot restart after
// MPI_Finalize. Under ctest it runs as a single rank (MPI's singleton start);
// tests/tools/run_mpi_unit_tests.sh runs it on three ranks under mpirun.
TEST(MpiCommunicator, KeepsTheCommunicatorContract) {
  MpiCommunicator comm(nullptr, nullptr);
  EXPECT_GE(comm.size(), 1);
  // The test's ranks all run on this machine; a group keeps the job's count.
  EXPECT_EQ(comm.ranksOnThisMachine(), comm.size());
  EXPECT_EQ(comm.split(comm.rank() % 2)->ranksOnThisMachine(), comm.size());
  testing::checkReductions(comm);
  testing::checkExchangeCounts(comm);
  testing::checkExchangeBytes(comm);
  testing::checkGathers(comm);
  testing::checkBroadcast(comm);
  // Messages above 4 KiB go in pieces here (1 GiB in real runs), so the
  // split path is exercised with small messages.
  comm.setMaxPieceBytes(4096);
  testing::checkMessages(comm, 3000);  // 24 KB: six pieces
  comm.setMaxPieceBytes(size_t(1) << 30);

  ::testing::internal::CaptureStderr();  // each rank is its own process
  std::vector<bool> agreed = testing::agreeOnFailureCases(comm);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(),
            comm.isRoot() ? testing::agreeOnFailureCasesStderr(comm.size()) : "");
  EXPECT_EQ(agreed, (std::vector<bool>{false, true, true}));

  // An MPI error comes back as a CommunicationError naming the call and the
  // rank: every rank sends itself 8 bytes but expects 4 (truncation).
  const int n = comm.size();
  std::vector<char> send(8, 'x'), receive(8);
  std::vector<int> sendCounts(n, 0), receiveCounts(n, 0), offsets(n, 0);
  sendCounts[comm.rank()] = 8;
  receiveCounts[comm.rank()] = 4;
  try {
    comm.exchangeBytes(send.data(), sendCounts, offsets, receive.data(), receiveCounts, offsets);
    ADD_FAILURE() << "a truncated exchange did not throw";
  } catch (const CommunicationError& e) {
    EXPECT_EQ(e.operation(), "MPI_Alltoallv");
    EXPECT_EQ(e.rank(), comm.rank());
    const std::string prefix = "MPI_Alltoallv on rank " + std::to_string(comm.rank()) + ": ";
    EXPECT_EQ(std::string(e.what()).substr(0, prefix.size()), prefix) << e.what();
    EXPECT_NE(std::string(e.what()).find("MPI error code"), std::string::npos) << e.what();
  }
  comm.barrier();  // the ranks still talk after an error that came back as a code
}

}  // namespace
}  // namespace ferry
