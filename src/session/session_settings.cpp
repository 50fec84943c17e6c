#include "session/session_settings.h"

#include <algorithm>

namespace ferry {

PartitionerOptions partitionerOptions(const SessionSettings& settings, int ranks) {
  PartitionerOptions p = settings.partitioning;
  p.partitioner = settings.partitioner ? settings.partitioner : &defaultPartitioner(ranks);
  p.seed = settings.render.seed;
  return p;
}

int workerThreads(int requested, int cores, int ranksOnMachine) {
  if (requested > 0) return requested;
  cores = std::max(cores, 1);
  if (ranksOnMachine <= 1) return cores;
  return std::clamp(2 * cores / ranksOnMachine, 1, cores);
}

}  // namespace ferry
