#!/usr/bin/env bash
# The MPI communicator's unit test (src/mpi/mpi_communicator_test.cpp) on
# three real ranks: the same contract the in-process communicator is tested
# against, and MPI errors coming back as CommunicationError on every rank.
# Usage: run_mpi_unit_tests.sh FERRY_TESTS SOURCE_DIR
set -euo pipefail
tests=$1
source_dir=$2
source "$source_dir/tests/tools/mpi_env.sh"
timeout 120 mpirun --oversubscribe -np 3 "$tests" --gtest_filter='MpiCommunicator.*' --gtest_brief=1
echo "mpi_communicator_test: passed on 3 ranks"
