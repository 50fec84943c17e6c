#include "partition/partitioner.h"

#include <fmt/format.h>

#include <algorithm>
#include <memory>

#include "core/clock.h"
#include "core/error.h"
#include "partition/hybrid_partitioner.h"
#include "partition/object_partitioner.h"
#include "partition/proxies.h"
#include "partition/ray_guided_partitioner.h"
#include "partition/spatial_partitioner.h"
#include "partition/split_loop.h"
#include "partition/units.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

bool isPaperPartitioner(const std::string& name) {
  const auto& six = paperPartitionerNames();
  return std::find(six.begin(), six.end(), name) != six.end();
}

// The scene rewritten for `options` and its units.
struct Prepared {
  uint64_t inputBytes = 0;
  SceneSplitReport split;
  UnitSet units;
};

Prepared prepare(Scene& scene, const PartitionerOptions& o) {
  Prepared p;
  p.inputBytes = summarize(scene).memory.total();
  SceneSplitOptions split;
  split.breakSingleInstanceObjects = o.breakObjects;
  if (o.name == "best" || o.name == "ray-guided")
    split.maxPieceBytes = o.maxPieceBytes > 0
                              ? o.maxPieceBytes
                              : std::max<uint64_t>(1, p.inputBytes / kBestPiecesPerScene);
  p.split = splitForPartitioning(scene, split);
  UnitOptions unitOptions;
  unitOptions.grouping = o.name == "object-naive" || o.name == "object-proxies"
                             ? UnitGrouping::Objects
                             : UnitGrouping::Instances;
  unitOptions.nonInstancedTogether = !o.breakObjects;
  p.units = extractUnits(scene, unitOptions);
  return p;
}

std::unique_ptr<PartSplitter> makeSplitter(const std::string& name, const UnitSet& units) {
  if (name == "spatial-simple")
    return std::make_unique<SpatialSplitter>(units, SpatialSplitRule::Median);
  if (name == "spatial-sah")
    return std::make_unique<SpatialSplitter>(units, SpatialSplitRule::CostFunction);
  // Only `best` also tries keeping each object's instances together (see
  // object_partitioner.h); bvh-style sorts instances by their own centres.
  return std::make_unique<CentroidSplitter>(units, name == "best");
}

// `best` after its splits: parts above kBestFinalBalance x an even share give
// units (single instances, an object's instances together, or a shared
// mesh's users) to lighter parts (part_assignment.h, without rays: bytes
// only), so that its largest part stays near an even share.
void balanceBest(const Prepared& p, int ranks, std::vector<Part>& parts) {
  if (int(parts.size()) != ranks) return;  // copies of parts: nothing to move
  refinePartsByRays(p.units, Hypergraph{}, parts,
                    kBestFinalBalance * double(p.inputBytes) / double(ranks));
}

uint64_t replicationBudget(const PartitionerOptions& o, uint64_t inputBytes) {
  return uint64_t(std::max(0.0, o.replicationBudget) * double(inputBytes));
}

}  // namespace

uint64_t PartitionStats::maxRankBytes() const {
  return rankBytes.empty() ? 0 : *std::max_element(rankBytes.begin(), rankBytes.end());
}

const std::vector<std::string>& partitionerNames() {
  static const std::vector<std::string> names = {"spatial-simple", "spatial-sah", "object-naive",
                                                 "object-proxies", "bvh-style",   "best",
                                                 "ray-guided",     "round-robin", "random"};
  return names;
}

const std::vector<std::string>& paperPartitionerNames() {
  static const std::vector<std::string> names(partitionerNames().begin(),
                                              partitionerNames().begin() + 6);
  return names;
}

void checkPartitionerName(const std::string& name) {
  parsePartitioner(name);
}

PartitionerKind parsePartitioner(const std::string& name) {
  const auto& all = partitionerNames();
  const auto found = std::find(all.begin(), all.end(), name);
  if (found != all.end()) return PartitionerKind(found - all.begin());
  std::string known;
  for (const std::string& n : all) known += (known.empty() ? "" : ", ") + n;
  throw InputError(fmt::format("unknown partitioner '{}' (partitioners: {})", name, known));
}

std::string toString(PartitionerKind kind) {
  const size_t index = size_t(kind);
  FERRY_CHECK_LT(index, partitionerNames().size());
  return partitionerNames()[index];
}

int instanceProxiesFor(const PartitionerOptions& o) {
  if (o.instanceProxies > 0) return o.instanceProxies;
  return o.name == "best" || o.name == "ray-guided" ? kShapeBoxesBySize : 1;
}

Partition partitionScene(Scene& scene, int ranks, const PartitionerOptions& o,
                         PartitionStats* stats) {
  const auto start = Clock::now();
  checkPartitionerName(o.name);
  if (ranks < 1 || ranks > kMaxRanks)
    throw InputError(fmt::format("{} ranks: partitions have 1 to {} ranks", ranks, kMaxRanks));
  PartitionStats local;
  PartitionStats& s = stats ? *stats : local;
  s = PartitionStats{};
  s.partitioner = o.name;
  s.ranks = ranks;

  Partition partition;
  bool merged = false;  // the braided partitioners merge their boxes themselves
  if (o.name == "round-robin" || o.name == "random") {
    s.inputBytes = summarize(scene).memory.total();
    partition = o.name == "round-robin" ? roundRobinPartition(scene, ranks)
                                        : randomPartition(scene, ranks, o.seed);
    s.parts = ranks;
    s.units = scene.instances.size();
  } else {
    Prepared p = prepare(scene, o);
    s.inputBytes = p.inputBytes;
    s.split = std::move(p.split);
    s.units = p.units.units.size();
    std::vector<Part> parts;
    if (o.name == "ray-guided") {
      if (!o.raySample)
        throw InternalError("the ray-guided partitioner was given no ray sample (withRaySample)");
      // Splits are weighed with one box per instance whatever the proxies:
      // the parts are those of one box per instance, and braided proxies
      // only tighten them. Weighed with the braided boxes the island's
      // parts forwarded 11 % more on its unseen view (docs/partitioning.md).
      const RayIncidence incidence =
          rayIncidence(unitProxyBoxes(scene, p.units, o.meshProxies, 1), *o.raySample);
      RayGuidedSplitter splitter(p.units, incidence, ranks, o.maxPart);
      parts = runSplitLoop(splitter, ranks);
      refinePartsByRays(
          p.units, incidence, parts,
          (o.maxPart - kRayGuidedRefineMargin) * double(p.inputBytes) / double(ranks));
      s.sampledRays = o.raySample->rays.size();
      s.sampledRaysAcrossUnits = incidence.rays();
      s.separatedRays = estimatedForwards(incidence, parts, p.units.units.size());
      s.sampleSeconds = o.raySample->seconds;
    } else {
      std::unique_ptr<PartSplitter> splitter = makeSplitter(o.name, p.units);
      parts = runSplitLoop(*splitter, ranks);
      if (o.name == "best") balanceBest(p, ranks, parts);
    }
    s.parts = int(parts.size());
    const std::vector<RankSet> partRanks = assignRanks(parts, ranks);
    std::vector<RankSet> owners = unitOwners(p.units, parts, partRanks);
    if (o.name == "best" || o.name == "ray-guided") {
      // Both keep their balance: no part above kBestMaxPart or
      // kRayGuidedMaxPart x an even share.
      const double share = double(p.inputBytes) / double(ranks);
      const uint64_t cap = uint64_t(
          (o.name == "best" ? kBestMaxPart : o.maxPart + kRayGuidedReplicationMargin) * share);
      ReplicationResult r = replicateLargeUnits(p.units, parts, partRanks, owners,
                                                replicationBudget(o, p.inputBytes), cap);
      s.replicatedBytes = r.addedBytes;
      s.replicatedUnits = r.replicatedUnits;
    }
    partition.ranks = ranks;
    partition.instanceOwners = instanceOwnersOf(p.units, owners);
    if (o.name == "spatial-simple" || o.name == "spatial-sah")
      partition.proxies = domainProxies(parts, partRanks);
    else if (o.name == "object-naive")
      partition.proxies = unitBoxProxies(p.units, owners);
    else if (o.name == "object-proxies" || o.name == "ray-guided" || o.name == "best") {
      // best: its mesh pieces braided too (docs/partitioning.md, "best's
      // proxies"), merged straight from the boxes. Braided instances are
      // instanced proxies (a transform each, their object's boxes held
      // once: docs/partitioning.md, "Instanced proxies"), one per instance
      // and never merged (each costs about what a box does in the proxy
      // tree); when they alone would reach --max-proxies, they are world
      // boxes instead, merged with the rest as before.
      int instanceBoxes = instanceProxiesFor(o);
      bool instanced = instanceBoxes != 1;
      uint64_t boxBudget = o.maxProxies;
      if (instanced && o.maxProxies > 0) {
        const uint64_t count = instancedInstanceCount(scene, p.units);
        instanced = count < o.maxProxies;
        if (instanced) boxBudget = o.maxProxies - count;
        // The instances alone exceed the budget, so their world boxes are
        // merged: finer boxes per instance would only be merged away, at a
        // cost in time and memory per instance (docs/partitioning.md, "At
        // scale"). The default gives the object's box.
        if (!instanced && instanceBoxes == kShapeBoxesBySize) instanceBoxes = 1;
        if (!instanced && instanceBoxes > kMaxWorldInstanceBoxes)
          throw InputError(fmt::format(
              "--instance-proxies {}: the scene's {} instances reach --max-proxies {}, so they "
              "would be world boxes, {} per mesh of every instance; raise --max-proxies above {} "
              "(or 0: no limit) or give at most {} boxes per mesh",
              instanceBoxes, count, o.maxProxies, instanceBoxes, count, kMaxWorldInstanceBoxes));
      }
      const std::vector<UnitBox> boxes =
          unitProxyBoxes(scene, p.units, o.meshProxies, instanceBoxes, !instanced);
      partition.proxies = mergeProxies(boxes, owners, boxBudget);
      const size_t boxProxies = partition.proxies.size();
      if (instanced) addInstancedProxies(scene, p.units, owners, instanceBoxes, partition);
      s.unmergedProxies = boxes.size() + (partition.proxies.size() - boxProxies);
      merged = true;
    } else
      partition.proxies = instanceProxies(scene, p.units, owners, 1);
  }
  if (!merged) {
    s.unmergedProxies = partition.proxies.size();
    partition.proxies = mergeProxies(std::move(partition.proxies), o.maxProxies);
  }
  s.proxies = partition.proxies.size();
  if (stats)  // a pass over the scene per rank: only when asked for
    for (int r = 0; r < ranks; ++r)
      s.rankBytes.push_back(ownedMemory(scene, partition.instancesOf(r)).total());
  s.seconds = secondsSince(start);
  return partition;
}

std::vector<uint64_t> maxPartBytesCurve(Scene& scene, const PartitionerOptions& o, int maxRanks) {
  if (!isPaperPartitioner(o.name))
    throw InputError(
        fmt::format("max-part curves are made for the paper's partitioners, not '{}'", o.name));
  FERRY_CHECK_GE(maxRanks, 1);
  Prepared p = prepare(scene, o);
  std::unique_ptr<PartSplitter> splitter = makeSplitter(o.name, p.units);
  std::vector<uint64_t> curve;
  const uint64_t budget = replicationBudget(o, p.inputBytes);
  runSplitLoop(*splitter, maxRanks, [&](const std::vector<Part>& parts) {
    uint64_t largest = 0;
    if (o.name == "best" && parts.size() > 1) {
      // One rank per part here (masks only count copies: one bit each).
      std::vector<Part> copy = parts;
      const size_t n = parts.size();  // balancing may empty (drop) parts
      balanceBest(p, int(n), copy);
      std::vector<RankSet> oneRank(copy.size(), RankSet::single(0));
      std::vector<RankSet> owners(p.units.units.size());
      replicateLargeUnits(p.units, copy, oneRank, owners, budget,
                          uint64_t(kBestMaxPart * double(p.inputBytes) / double(n)));
      for (const Part& part : copy) largest = std::max(largest, part.bytes);
    } else {
      for (const Part& part : parts) largest = std::max(largest, part.bytes);
    }
    curve.push_back(largest);
  });
  // The loop stops early when nothing can be split: more ranks hold copies,
  // and the largest part stays as it is.
  while (int(curve.size()) < maxRanks) curve.push_back(curve.back());
  return curve;
}

}  // namespace ferry
