// A Ferry session on an application's own MPI communicator: every rank of
// `comm` renders together; the other ranks of the job are never involved.
// MPI must be running (MPI_Init by the application); Ferry talks only on
// duplicates of `comm` and never finalizes MPI.
#pragma once

#include <mpi.h>

#include "ferry/ferry.h"

namespace ferry::api {

inline Session sessionOn(MPI_Comm comm, const Options& options = {}) {
  return Session(int(MPI_Comm_c2f(comm)), options);
}

}  // namespace ferry::api
