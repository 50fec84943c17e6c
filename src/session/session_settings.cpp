#include "session/session_settings.h"

namespace ferry {

PartitionerOptions partitionerOptions(const SessionSettings& settings, int ranks) {
  PartitionerOptions p;
  p.name = toString(settings.partitioner.value_or(ranks > 1 ? PartitionerKind::Best
                                                            : PartitionerKind::RoundRobin));
  p.breakObjects = !settings.keepObjectsWhole;
  p.replicationBudget = settings.replicationBudget;
  p.maxPart = settings.maxPart;
  p.maxProxies = settings.maxProxies;
  p.seed = settings.render.seed;
  return p;
}

}  // namespace ferry
