// The library's Session over any Communicator: the public constructors use
// it (one process, an application's MPI communicator), `ferry render` uses it
// on the job's ranks, tests with in-process ranks.
#pragma once

#include <memory>

#include "comm/communicator.h"
#include "ferry/ferry.h"

namespace ferry {

// A session on `comm`, which `keep` (may be null) keeps alive as long as the session.
api::Session sessionOn(const Communicator& comm, std::shared_ptr<const void> keep,
                       const api::Options& options);

}  // namespace ferry
