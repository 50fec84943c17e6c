// Everything a render session needs to know, parsed and checked: the command
// line (app/) builds it; the session never reads a flag.
#pragma once

#include <string>

#include "distributed/distributed_traversal.h"
#include "distributed/forwarding.h"
#include "io/load_options.h"
#include "partition/partitioner.h"

#include <optional>
#include "render/wavefront_renderer.h"
#include "session/modes.h"
#include "shapes/volume_brick.h"

namespace ferry {

struct SessionSettings {
  // A scene file, a built-in (builtin:NAME?...) or a part directory (ferry partition -o DIR).
  std::string scene;
  // How a scene file is loaded, and how the loaders talk back on this rank.
  LoadOptions load;
  // Image size, samples, frames, depth, seed, view, tone mapping. Its
  // retraceAll is the session's to set, from `retrace`.
  RenderSettings render;
  int threads = 0;  // worker threads per rank (0: workerThreads chooses)
  // Grid volumes that fill their box are split into bricks of this many
  // voxels a side, spread over the ranks (shapes/volume_brick.h);
  // kAutoBricks: large grids only, sized by autoBrickVoxels; 0: every rank
  // holds every medium whole.
  int volumeBrickVoxels = kAutoBricks;
  // Data groups (hybrid data and image parallelism): the ranks split into
  // this many groups of equal size, each holding the whole scene spread over
  // its ranks (a part directory for that many ranks) and rendering every
  // dataGroups-th sample. The same image as one group.
  int dataGroups = 1;
  // Light paths (--light-paths on/off); none given: as the scene's
  // integrator asks (integratorWantsLightPaths). Sets render.lightPaths.
  std::optional<bool> lightPaths;

  ForwardingMode forwarding = ForwardingMode::Proxies;
  ExchangeMode exchange = ExchangeMode::Auto;
  PathLayout pathLayout = PathLayout::Auto;
  Retrace retrace = Retrace::Remote;
  Instancing instancing = Instancing::Shared;

  // How a scene (not a part directory) is split over the ranks, on the fly:
  // every rank runs the same deterministic partitioner. None given: the
  // paper's best on more than one rank (round-robin, which does nothing, on one).
  const Partitioner* partitioner = nullptr;

  // Long renders (io/checkpoints/checkpoint_file.h): the accumulated image is written to
  // `checkpoint` every `checkpointEvery` frames and after the last one;
  // `timeLimitSeconds` (> 0) makes the frame that crosses it the last.
  std::string checkpoint;
  int checkpointEvery = 10;
  double timeLimitSeconds = 0;
  // The partitioner's settings; partitionerOptions adds the partitioner
  // (from `partitioner` and the rank count) and the seed (render.seed).
  PartitionerOptions partitioning;
};

// The partitioner options a session with `settings` partitions with on `ranks` ranks.
PartitionerOptions partitionerOptions(const SessionSettings& settings, int ranks);

// The worker threads a rank runs: `requested` when set (> 0); else all
// `cores` it may use, unless `ranksOnMachine` ranks share them: then each
// runs 2 * cores / ranksOnMachine (at least 1, at most `cores`), twice the
// cores in all, so that a busy rank takes the cores an idle one leaves,
// and no more threads wait their turn than that (docs/guide.md, --threads).
int workerThreads(int requested, int cores, int ranksOnMachine);

}  // namespace ferry
