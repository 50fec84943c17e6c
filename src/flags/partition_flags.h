// The flags that say how a scene is split over ranks, shared by `ferry
// partition` (which writes the parts) and `ferry render` / `ferry view`
// (which split the scene on the fly): made from the partitioner registry
// and its settings (partition/partitioner.h), one flag per setting.
#pragma once

#include <string>

#include "partition/partitioner.h"

namespace CLI {
class App;
}

namespace ferry {

struct PartitionFlags {
  // --partitioner: a name from partitioners(); empty: the command's default.
  std::string partitioner;
  // Every setting's flag; `partitioner`, `seed` and `raySample` are the command's to set.
  PartitionerOptions options;
};

// Adds --partitioner (its help lists the registry) and --NAME for every
// partitioner setting, with the setting's help and the partitioners that read it.
// `partitionerFlag` is the option's names (e.g. "--partitioner,--partition");
// `defaultText` ends --partitioner's help: what the command does when it is not given.
void addPartitionFlags(CLI::App* command, PartitionFlags& flags, const std::string& partitionerFlag,
                       const std::string& defaultText);

// The flags as partitioner options, checked: throws InputError naming the
// flag and its range. The partitioner and seed are left unset.
PartitionerOptions checkedPartitionerOptions(const PartitionFlags& flags);

// The partitioner --partitioner names, or `fallback` when none is given;
// throws InputError naming the accepted ones.
const Partitioner& chosenPartitioner(const PartitionFlags& flags, const Partitioner& fallback);

}  // namespace ferry
