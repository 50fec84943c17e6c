// The flags that say how a scene is split over ranks, shared by `ferry
// partition` (which writes the parts) and `ferry render` / `ferry view`
// (which split the scene on the fly, every rank alike): one definition, one
// help text and one check for both, so the two commands cannot drift apart.
#pragma once

#include <string>

#include "partition/partitioner.h"

namespace CLI {
class App;
}

namespace ferry {

struct PartitionFlags {
  // --partitioner: a name from partitionerNames(); empty: the command's default.
  std::string partitioner;
  bool keepObjectsWhole = false;  // --keep-objects-whole (options.breakObjects is its opposite)
  // Every other flag's value, its default the partitioner's own. name,
  // seed and raySample are the command's to set.
  PartitionerOptions options;
};

// Adds --partitioner, --keep-objects-whole, --replication-budget,
// --mesh-proxies, --instance-proxies, --max-part, --max-proxies and
// --ray-paths. `partitionerNames` is the option's names (e.g.
// "--partitioner,--partition"); `defaultText` ends --partitioner's help: what
// the command does when it is not given.
void addPartitionFlags(CLI::App* command, PartitionFlags& flags,
                       const std::string& partitionerNames, const std::string& defaultText);

// The flags as partitioner options, checked: throws InputError naming the
// flag and its range. The name and seed are left as `flags.options` has them.
PartitionerOptions checkedPartitionerOptions(const PartitionFlags& flags);

}  // namespace ferry
