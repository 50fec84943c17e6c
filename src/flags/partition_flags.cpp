#include "flags/partition_flags.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "core/error.h"

namespace ferry {

void addPartitionFlags(CLI::App* command, PartitionFlags& f, const std::string& partitionerFlag,
                       const std::string& defaultText) {
  std::string help = "How the scene is split over ranks, one of:\n";
  for (const Partitioner* p : partitioners())
    help += fmt::format("  {:<15} {}\n", p->name(), p->summary());
  command->add_option(partitionerFlag, f.partitioner, help + defaultText);
  for (const PartitionerSetting& s : partitionerSettings()) {
    std::string readers;
    size_t count = 0;
    for (const Partitioner* p : partitioners())
      if (p->reads(s.name)) {
        readers += (readers.empty() ? "" : ", ") + std::string(p->name());
        ++count;
      }
    const std::string flag = "--" + std::string(s.name);
    const std::string text = fmt::format(
        "{}\n({})", s.help,
        count == partitioners().size() ? std::string("every partitioner") : "read by " + readers);
    std::visit(
        [&](auto field) {
          using T = std::remove_reference_t<decltype(f.options.*field)>;
          if constexpr (std::is_same_v<T, bool>)
            command->add_flag(flag, f.options.*field, text);
          else
            command->add_option(flag, f.options.*field, text)->capture_default_str();
        },
        s.field);
  }
}

PartitionerOptions checkedPartitionerOptions(const PartitionFlags& f) {
  const PartitionerOptions& p = f.options;
  if (const PartitionerSetting* s = firstSettingOutOfRange(p))
    throw InputError(fmt::format("--{} {}: expected {}", s->name, s->valueText(p), s->rangeText()));
  return p;
}

const Partitioner& chosenPartitioner(const PartitionFlags& f, const Partitioner& fallback) {
  return f.partitioner.empty() ? fallback : partitionerNamed(f.partitioner);
}

}  // namespace ferry
