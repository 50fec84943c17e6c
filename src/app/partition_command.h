// `ferry partition`: split a scene into one part file per rank (plus shared
// data and a manifest) for `ferry render DIR`, or report how large the
// largest part gets for each partitioner over a range of rank counts.
// Also the `--show-partition` pictures of `ferry render`.
#pragma once

#include <string>

#include "partition/partitioner.h"

namespace CLI {
class App;
}

namespace ferry {

class Communicator;
struct RenderOptions;

struct PartitionCommandOptions {
  std::string scene = "builtin:island";
  std::string ranks = "8";
  std::string partitioner = "best";
  std::string output;  // part directory
  std::string report;  // CSV of the largest part per rank count
  std::string plot;    // PNG of the same (default: the report's name with .png)
  bool keepObjectsWhole = false;
  double replicationBudget = 0.05;
  int meshProxies = 64;
  bool quiet = false;
};

void addPartitionCommand(CLI::App& app, PartitionCommandOptions& options);
int runPartition(const PartitionCommandOptions& options);

// `ferry render --show-partition[=N]`: rank 0 draws the partition (of a part
// directory, or made on the fly for N ranks, default the MPI rank count) and
// writes it as PNG; the other ranks only agree on failure.
int runShowPartition(const RenderOptions& options, const Communicator& comm);

}  // namespace ferry
