#include "partition/partitioner.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/clock.h"
#include "core/error.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {

uint64_t PartitionStats::maxRankBytes() const {
  return rankBytes.empty() ? 0 : *std::max_element(rankBytes.begin(), rankBytes.end());
}

const Partitioner& PartitionerOptions::chosen() const {
  return partitioner ? *partitioner : bestPartitioner();
}

const std::vector<PartitionerSetting>& partitionerSettings() {
  static const std::vector<PartitionerSetting> settings = {
      {"keep-objects-whole",
       "Keep non-instanced content whole, as one unit (default: each mesh of a non-instanced\n"
       "object is its own unit, after Zellmann et al.)",
       &PartitionerOptions::keepObjectsWhole},
      {"replication-budget",
       "Copies of spatially large, cheap content may add this fraction of the scene's bytes",
       &PartitionerOptions::replicationBudget, 0, 1, "a fraction from 0 to 1"},
      {"mesh-proxies",
       "Boxes per non-instanced mesh or mesh piece, made by BVH build steps on its triangles\n"
       "(braiding); 1: its box",
       &PartitionerOptions::meshProxies, 1, 4096},
      {"instance-proxies",
       "Boxes per mesh of an instanced object (braiding in object space); above 1 each\n"
       "instance is one instanced proxy, its transform and its object's boxes, held once per\n"
       "object; 1: one box per instance. Default (or 0): for best and ray-guided one box per 4\n"
       "triangles of each mesh, at most 1024 (about 30 B per box on every rank), 1 for\n"
       "object-proxies (the paper's one box per instance); at most 64 when the instances would\n"
       "reach max-proxies (they are then world boxes, merged; the default gives 1 there)",
       &PartitionerOptions::instanceProxies, 0, kMaxInstanceProxies,
       fmt::format("1 to {} (0: the default)", kMaxInstanceProxies)},
      {"max-part",
       "The largest part it aims at, times an even share (total / ranks); a larger factor\n"
       "trades memory per rank for fewer forwarded rays",
       &PartitionerOptions::maxPart, 1, 1e6, "a factor of at least 1"},
      {"max-proxies",
       "Merge proxies with the same owners into union boxes until there are at most this many\n"
       "(0: never). Every rank holds every world-box proxy (~90 B each); merged boxes only cost\n"
       "rays sent through their gaps",
       &PartitionerOptions::maxProxies, 0, 1.9e19},
      {"ray-paths",
       "Paths in its ray sample (each a few rays), traced from cameras spread around and inside\n"
       "the scene, never from its named views",
       &PartitionerOptions::rayPaths, 1, double(uint64_t(1) << 26)},
  };
  return settings;
}

std::string PartitionerSetting::rangeText() const {
  return range.empty() ? fmt::format("{} to {}", min, max) : range;
}

std::string PartitionerSetting::valueText(const PartitionerOptions& o) const {
  return std::visit([&](auto f) { return fmt::format("{}", o.*f); }, field);
}

const PartitionerSetting* firstSettingOutOfRange(const PartitionerOptions& o) {
  for (const PartitionerSetting& s : partitionerSettings()) {
    if (std::holds_alternative<bool PartitionerOptions::*>(s.field)) continue;
    const double value = std::visit([&](auto f) { return double(o.*f); }, s.field);
    if (!(value >= s.min && value <= s.max)) return &s;
  }
  return nullptr;
}

void checkPartitionerOptions(const PartitionerOptions& o) {
  if (const PartitionerSetting* s = firstSettingOutOfRange(o))
    throw InputError(fmt::format("partitioner setting {} = {}: expected {}", s->name,
                                 s->valueText(o), s->rangeText()));
}

bool Partitioner::reads(std::string_view setting) const {
  if (setting == "max-proxies") return true;
  const std::vector<std::string_view> mine = settings();
  return std::find(mine.begin(), mine.end(), setting) != mine.end();
}

std::vector<uint64_t> Partitioner::maxPartBytesCurve(Scene&, const PartitionerOptions&, int) const {
  throw InputError(
      fmt::format("max-part curves are made for the paper's partitioners, not '{}'", name()));
}

const std::vector<std::string>& partitionerNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> all;
    for (const Partitioner* p : partitioners()) all.emplace_back(p->name());
    return all;
  }();
  return names;
}

const std::vector<std::string>& paperPartitionerNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> six;
    for (const Partitioner* p : partitioners())
      if (p->fromThePaper()) six.emplace_back(p->name());
    return six;
  }();
  return names;
}

const Partitioner& partitionerNamed(std::string_view name) {
  std::string known;
  for (const Partitioner* p : partitioners()) {
    if (p->name() == name) return *p;
    known += (known.empty() ? "" : ", ") + std::string(p->name());
  }
  throw InputError(fmt::format("unknown partitioner '{}' (partitioners: {})", name, known));
}

int instanceProxiesFor(const PartitionerOptions& o) {
  return o.instanceProxies > 0 ? o.instanceProxies : o.chosen().defaultInstanceBoxes();
}

void mergePartitionProxies(Partition& partition, const PartitionerOptions& o,
                           PartitionStats& stats) {
  stats.unmergedProxies = partition.proxies.size();
  partition.proxies = mergeProxies(std::move(partition.proxies), o.maxProxies);
}

Partition partitionScene(Scene& scene, int ranks, const PartitionerOptions& o,
                         PartitionStats* stats) {
  const auto start = Clock::now();
  checkPartitionerOptions(o);
  if (ranks < 1 || ranks > kMaxRanks)
    throw InputError(fmt::format("{} ranks: partitions have 1 to {} ranks", ranks, kMaxRanks));
  PartitionStats local;
  PartitionStats& s = stats ? *stats : local;
  s = PartitionStats{};
  const Partitioner& partitioner = o.chosen();
  s.partitioner = partitioner.name();
  s.ranks = ranks;
  Partition partition = partitioner.partition(scene, ranks, o, s);
  s.proxies = partition.proxies.size();
  if (stats)  // a pass over the scene per rank: only when asked for
    for (int r = 0; r < ranks; ++r)
      s.rankBytes.push_back(ownedMemory(scene, partition.instancesOf(r)).total());
  s.seconds = secondsSince(start);
  return partition;
}

std::vector<uint64_t> maxPartBytesCurve(Scene& scene, const PartitionerOptions& o, int maxRanks) {
  FERRY_CHECK_GE(maxRanks, 1);
  checkPartitionerOptions(o);
  return o.chosen().maxPartBytesCurve(scene, o, maxRanks);
}

}  // namespace ferry
