#include "session/session_settings.h"

namespace ferry {

PartitionerOptions partitionerOptions(const SessionSettings& settings, int ranks) {
  PartitionerOptions p = settings.partitioning;
  p.partitioner = settings.partitioner ? settings.partitioner : &defaultPartitioner(ranks);
  p.seed = settings.render.seed;
  return p;
}

}  // namespace ferry
