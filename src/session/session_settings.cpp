#include "session/session_settings.h"

namespace ferry {

PartitionerOptions partitionerOptions(const SessionSettings& settings, int ranks) {
  PartitionerOptions p = settings.partitioning;
  p.name = toString(settings.partitioner.value_or(ranks > 1 ? PartitionerKind::Best
                                                            : PartitionerKind::RoundRobin));
  p.seed = settings.render.seed;
  return p;
}

}  // namespace ferry
