#include "app/partition_flags.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "core/error.h"

namespace ferry {

void addPartitionFlags(CLI::App* command, PartitionFlags& f, const std::string& partitionerNames,
                       const std::string& defaultText) {
  std::string names;
  for (const std::string& n : ferry::partitionerNames()) names += (names.empty() ? "" : ", ") + n;
  command->add_option(partitionerNames, f.partitioner,
                      "How the scene is split over ranks, one of\n" + names + ".\n" + defaultText);
  command->add_flag(
      "--keep-objects-whole", f.keepObjectsWhole,
      "Keep non-instanced content whole, as one unit (default: each mesh of a non-instanced\n"
      "object is its own unit, after Zellmann et al.)");
  PartitionerOptions& o = f.options;
  command
      ->add_option("--replication-budget", o.replicationBudget,
                   "best, ray-guided: copies of spatially large, cheap content may add this\n"
                   "fraction of the scene's bytes")
      ->capture_default_str();
  command
      ->add_option("--mesh-proxies", o.meshProxies,
                   "object-proxies, best, ray-guided: boxes per non-instanced mesh or mesh\n"
                   "piece, made by BVH build steps on its triangles (braiding); 1: its box")
      ->capture_default_str();
  command
      ->add_option("--instance-proxies", o.instanceProxies,
                   "object-proxies, best, ray-guided: boxes per mesh of an instanced object\n"
                   "(braiding in object space); above 1 each instance is one instanced proxy, its\n"
                   "transform and its object's boxes, held once per object; 1: one box per\n"
                   "instance. Default (or 0): for best and ray-guided one box per 4 triangles of\n"
                   "each mesh, at most 1024 (10-22 % fewer forwards than 64 per mesh, about 30 B\n"
                   "per box on every rank), 1 for object-proxies (the paper's one box per\n"
                   "instance); at most 1024, and at most 64 when the instances would reach\n"
                   "--max-proxies (they are then world boxes, merged; the default gives 1 there)")
      ->capture_default_str();
  command
      ->add_option("--max-part", o.maxPart,
                   "ray-guided: the largest part it aims at, times an even share (total / ranks);\n"
                   "a larger factor trades memory per rank for fewer forwarded rays")
      ->capture_default_str();
  command
      ->add_option("--max-proxies", o.maxProxies,
                   "Merge proxies with the same owners into union boxes until there are at most\n"
                   "this many (0: never). Every rank holds every world-box proxy (~90 B each);\n"
                   "merged boxes only cost rays sent through their gaps")
      ->capture_default_str();
  command
      ->add_option("--ray-paths", o.rayPaths,
                   "ray-guided: paths in its ray sample (each a few rays), traced from cameras\n"
                   "spread around and inside the scene, never from its named views")
      ->capture_default_str();
}

PartitionerOptions checkedPartitionerOptions(const PartitionFlags& f) {
  PartitionerOptions p = f.options;
  p.breakObjects = !f.keepObjectsWhole;
  if (!(p.replicationBudget >= 0 && p.replicationBudget <= 1))
    throw InputError(fmt::format("--replication-budget {}: expected a fraction from 0 to 1",
                                 p.replicationBudget));
  if (!(p.maxPart >= 1 && p.maxPart <= 1e6))
    throw InputError(fmt::format("--max-part {}: expected a factor of at least 1", p.maxPart));
  if (p.rayPaths < 1 || p.rayPaths > (uint64_t(1) << 26))
    throw InputError(
        fmt::format("--ray-paths {}: expected 1 to {}", p.rayPaths, uint64_t(1) << 26));
  if (p.meshProxies < 1 || p.meshProxies > 4096)
    throw InputError(fmt::format("--mesh-proxies {}: expected 1 to 4096", p.meshProxies));
  if (p.instanceProxies < 0 || p.instanceProxies > kMaxInstanceProxies)
    throw InputError(fmt::format("--instance-proxies {}: expected 1 to {} (0: the default)",
                                 p.instanceProxies, kMaxInstanceProxies));
  return p;
}

}  // namespace ferry
