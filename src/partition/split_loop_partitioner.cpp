#include "partition/split_loop_partitioner.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"
#include "partition/hybrid_partitioner.h"
#include "partition/object_partitioner.h"
#include "partition/proxies.h"
#include "partition/spatial_partitioner.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {

uint64_t replicationBudget(const PartitionerOptions& o, uint64_t inputBytes) {
  return uint64_t(std::max(0.0, o.replicationBudget) * double(inputBytes));
}

SplitLoopPartitioner::Prepared SplitLoopPartitioner::prepare(Scene& scene,
                                                             const PartitionerOptions& o) const {
  Prepared p;
  p.scene = &scene;
  p.inputBytes = summarize(scene).memory.total();
  SceneSplitOptions split;
  split.breakSingleInstanceObjects = !o.keepObjectsWhole;
  if (cutsMeshes())
    split.maxPieceBytes = o.maxPieceBytes > 0
                              ? o.maxPieceBytes
                              : std::max<uint64_t>(1, p.inputBytes / kBestPiecesPerScene);
  p.split = splitForPartitioning(scene, split);
  UnitOptions unitOptions;
  unitOptions.grouping = grouping();
  unitOptions.nonInstancedTogether = o.keepObjectsWhole;
  p.units = extractUnits(scene, unitOptions);
  return p;
}

std::unique_ptr<PartSplitter> SplitLoopPartitioner::splitter(const UnitSet& units) const {
  return std::make_unique<CentroidSplitter>(units, false);
}

std::vector<Part> SplitLoopPartitioner::split(const Prepared& p, int ranks,
                                              const PartitionerOptions&, PartitionStats&) const {
  return runSplitLoop(*splitter(p.units), ranks);
}

uint64_t SplitLoopPartitioner::largestPart(const Prepared&, std::vector<Part> parts,
                                           const PartitionerOptions&) const {
  uint64_t largest = 0;
  for (const Part& part : parts) largest = std::max(largest, part.bytes);
  return largest;
}

Partition SplitLoopPartitioner::partition(Scene& scene, int ranks, const PartitionerOptions& o,
                                          PartitionStats& s) const {
  Prepared p = prepare(scene, o);
  s.inputBytes = p.inputBytes;
  s.split = std::move(p.split);
  s.units = p.units.units.size();
  std::vector<Part> parts = split(p, ranks, o, s);
  s.parts = int(parts.size());
  const std::vector<RankSet> partRanks = assignRanks(parts, ranks);
  std::vector<RankSet> owners = unitOwners(p.units, parts, partRanks);
  if (const double cap = replicationCap(o); cap > 0) {
    const double share = double(p.inputBytes) / double(ranks);
    ReplicationResult r =
        replicateLargeUnits(p.units, parts, partRanks, owners, replicationBudget(o, p.inputBytes),
                            uint64_t(cap * share));
    s.replicatedBytes = r.addedBytes;
    s.replicatedUnits = r.replicatedUnits;
  }
  Partition partition;
  partition.ranks = ranks;
  partition.instanceOwners = instanceOwnersOf(p.units, owners);
  makeProxies(scene, p, parts, partRanks, owners, o, partition, s);
  return partition;
}

void SplitLoopPartitioner::makeProxies(const Scene& scene, const Prepared& p,
                                       const std::vector<Part>& parts,
                                       const std::vector<RankSet>& partRanks,
                                       const std::vector<RankSet>& owners,
                                       const PartitionerOptions& o, Partition& partition,
                                       PartitionStats& s) const {
  switch (proxyKind()) {
    case ProxyKind::Domains:
      partition.proxies = domainProxies(parts, partRanks);
      break;
    case ProxyKind::UnitBoxes:
      partition.proxies = unitBoxProxies(p.units, owners);
      break;
    case ProxyKind::Instances:
      partition.proxies = instanceProxies(scene, p.units, owners, 1);
      break;
    case ProxyKind::Braided: {
      // Mesh boxes are merged straight from the boxes. Instances of
      // instanced objects are instanced proxies (their object's boxes held
      // once), never merged; when they alone reach max-proxies they are
      // world boxes, merged with the rest, and the default gives each the
      // object's box (finer boxes would only be merged away).
      int instanceBoxes = instanceProxiesFor(o);
      bool instanced = instanceBoxes != 1;
      uint64_t boxBudget = o.maxProxies;
      if (instanced && o.maxProxies > 0) {
        const uint64_t count = instancedInstanceCount(scene, p.units);
        instanced = count < o.maxProxies;
        if (instanced) boxBudget = o.maxProxies - count;
        if (!instanced && instanceBoxes == kShapeBoxesBySize) instanceBoxes = 1;
        if (!instanced && instanceBoxes > kMaxWorldInstanceBoxes)
          throw InputError(fmt::format(
              "instance-proxies {}: the scene's {} instances reach max-proxies {}, so they "
              "would be world boxes, {} per mesh of every instance; raise max-proxies above {} "
              "(or 0: no limit) or give at most {} boxes per mesh",
              instanceBoxes, count, o.maxProxies, instanceBoxes, count, kMaxWorldInstanceBoxes));
      }
      const std::vector<UnitBox> boxes =
          unitProxyBoxes(scene, p.units, o.meshProxies, instanceBoxes, !instanced);
      partition.proxies = mergeProxies(boxes, owners, boxBudget);
      const size_t boxProxies = partition.proxies.size();
      if (instanced) addInstancedProxies(scene, p.units, owners, instanceBoxes, partition);
      s.unmergedProxies = boxes.size() + (partition.proxies.size() - boxProxies);
      return;
    }
  }
  mergePartitionProxies(partition, o, s);
}

std::vector<uint64_t> SplitLoopPartitioner::maxPartBytesCurve(Scene& scene,
                                                              const PartitionerOptions& o,
                                                              int maxRanks) const {
  if (!fromThePaper()) return Partitioner::maxPartBytesCurve(scene, o, maxRanks);
  Prepared p = prepare(scene, o);
  std::unique_ptr<PartSplitter> s = splitter(p.units);
  std::vector<uint64_t> curve;
  runSplitLoop(*s, maxRanks,
               [&](const std::vector<Part>& parts) { curve.push_back(largestPart(p, parts, o)); });
  // The loop stops early when nothing can be split: more ranks hold copies,
  // and the largest part stays as it is.
  while (int(curve.size()) < maxRanks) curve.push_back(curve.back());
  return curve;
}

}  // namespace ferry
