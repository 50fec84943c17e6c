// `ferry partition`: split a scene into one part file per rank (plus shared
// data and a manifest) for `ferry render DIR`, or report how large the
// largest part gets for each partitioner over a range of rank counts.
// Also the `--show-partition` pictures of `ferry render`.
#pragma once

#include <cstdint>
#include <string>

#include "flags/camera_flags.h"
#include "flags/partition_flags.h"

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
  std::string output;  // part directory
  std::string report;  // CSV of the largest part per rank count
  std::string plot;    // PNG of the same (default: the report's name with .png)
  // --partitioner (default best) and the partitioners' flags, --seed among them.
  PartitionFlags partition;
  bool quiet = false;
  // --memory-budget: partition without holding the geometry when it would
  // not fit (empty: half the machine's memory; see partition_command.cpp).
  std::string memoryBudget;
  // --predict-forwards: after writing, estimate the rays forwarded per camera
  // path for each named view (and the --look-from camera), without MPI
  // (session/forward_prediction.h); printed and kept in manifest.json.
  bool predictForwards = false;
  uint64_t predictPaths = 16384;
  std::string predictSize = "2560x1080";
  int predictDepth = 5;
  CameraFlags camera;
  // --volume-bricks: auto, 0 (whole) or N (bricks of N voxels a side), as
  // for render (shapes/volume_brick.h).
  std::string volumeBricks = "auto";
};

void addPartitionCommand(CLI::App& app, PartitionCommandOptions& options);
int runPartition(const PartitionCommandOptions& options);

// `ferry render --show-partition[=N]`: rank 0 draws the partition (of a part
// directory, or made on the fly for N ranks, default the MPI rank count) and
// writes it as PNG; the other ranks only agree on failure.
int runShowPartition(const RenderOptions& options, const Communicator& comm);

}  // namespace ferry
