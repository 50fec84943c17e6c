#include "session/session_settings.h"

namespace ferry {

PartitionerOptions partitionerOptions(const SessionSettings& settings) {
  PartitionerOptions p;
  p.name = toString(settings.partitioner);
  p.breakObjects = !settings.keepObjectsWhole;
  p.replicationBudget = settings.replicationBudget;
  p.seed = settings.render.seed;
  return p;
}

}  // namespace ferry
