// The partitioners (partitioner.h): each declares its name, the settings it
// reads and its own steps; partitioners() is the registry. The paper's six
// (Section 4) come first, then Ferry's ray-guided, then two that test the
// distributed layer. docs/partitioning.md describes each.
#include <memory>

#include "partition/hybrid_partitioner.h"
#include "partition/object_partitioner.h"
#include "partition/partitioner.h"
#include "partition/ray_guided_partitioner.h"
#include "partition/ray_sampler.h"
#include "partition/spatial_partitioner.h"
#include "partition/split_loop_partitioner.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

class SpatialPartitioner : public SplitLoopPartitioner {
 public:
  bool fromThePaper() const override { return true; }
  std::vector<std::string_view> settings() const override { return {"keep-objects-whole"}; }

 protected:
  ProxyKind proxyKind() const override { return ProxyKind::Domains; }
};

class SpatialSimple final : public SpatialPartitioner {
 public:
  std::string_view name() const override { return "spatial-simple"; }
  std::string_view summary() const override {
    return "domains split at the spatial median of the longest axis; straddling content on "
           "both sides; proxies: the domains";
  }

 protected:
  std::unique_ptr<PartSplitter> splitter(const UnitSet& units) const override {
    return std::make_unique<SpatialSplitter>(units, SpatialSplitRule::Median);
  }
};

class SpatialSah final : public SpatialPartitioner {
 public:
  std::string_view name() const override { return "spatial-sah"; }
  std::string_view summary() const override {
    return "as spatial-simple, with the best of 3 x 7 planes by a surface-area cost";
  }

 protected:
  std::unique_ptr<PartSplitter> splitter(const UnitSet& units) const override {
    return std::make_unique<SpatialSplitter>(units, SpatialSplitRule::CostFunction);
  }
};

class ObjectNaive final : public SplitLoopPartitioner {
 public:
  std::string_view name() const override { return "object-naive"; }
  std::string_view summary() const override {
    return "whole objects (all instances on one rank) by their box centres; proxies: the "
           "objects' boxes";
  }
  bool fromThePaper() const override { return true; }
  std::vector<std::string_view> settings() const override { return {"keep-objects-whole"}; }

 protected:
  UnitGrouping grouping() const override { return UnitGrouping::Objects; }
  ProxyKind proxyKind() const override { return ProxyKind::UnitBoxes; }
};

class ObjectProxies final : public SplitLoopPartitioner {
 public:
  std::string_view name() const override { return "object-proxies"; }
  std::string_view summary() const override {
    return "object-naive's parts; proxies: one per instance, and boxes per non-instanced mesh "
           "by BVH build steps (braiding)";
  }
  bool fromThePaper() const override { return true; }
  std::vector<std::string_view> settings() const override {
    return {"keep-objects-whole", "mesh-proxies", "instance-proxies"};
  }

 protected:
  UnitGrouping grouping() const override { return UnitGrouping::Objects; }
  ProxyKind proxyKind() const override { return ProxyKind::Braided; }
};

class BvhStyle final : public SplitLoopPartitioner {
 public:
  std::string_view name() const override { return "bvh-style"; }
  std::string_view summary() const override {
    return "instances as units (objects copied where instances land); one proxy per instance "
           "or non-instanced mesh";
  }
  bool fromThePaper() const override { return true; }
  std::vector<std::string_view> settings() const override { return {"keep-objects-whole"}; }

 protected:
  ProxyKind proxyKind() const override { return ProxyKind::Instances; }
};

// Parts above kBestFinalBalance x an even share give units to lighter ones
// (part_assignment.h, bytes only).
void balanceByBytes(const UnitSet& units, uint64_t inputBytes, int ranks,
                    std::vector<Part>& parts) {
  if (int(parts.size()) != ranks) return;  // copies of parts: nothing to move
  refinePartsByRays(units, Hypergraph{}, parts,
                    kBestFinalBalance * double(inputBytes) / double(ranks));
}

class Best final : public SplitLoopPartitioner {
 public:
  std::string_view name() const override { return "best"; }
  std::string_view summary() const override {
    return "large meshes cut into pieces, then as bvh-style keeping objects' instances "
           "together where it can, parts balanced, large cheap content copied to every rank; "
           "braided proxies (Ferry's, beyond the paper)";
  }
  bool fromThePaper() const override { return true; }
  bool cutsMeshes() const override { return true; }
  int defaultInstanceBoxes() const override { return kShapeBoxesBySize; }
  std::vector<std::string_view> settings() const override {
    return {"keep-objects-whole", "replication-budget", "mesh-proxies", "instance-proxies"};
  }

 protected:
  ProxyKind proxyKind() const override { return ProxyKind::Braided; }
  std::unique_ptr<PartSplitter> splitter(const UnitSet& units) const override {
    return std::make_unique<CentroidSplitter>(units, true);
  }
  std::vector<Part> split(const Prepared& p, int ranks, const PartitionerOptions& o,
                          PartitionStats& s) const override {
    std::vector<Part> parts = SplitLoopPartitioner::split(p, ranks, o, s);
    balanceByBytes(p.units, p.inputBytes, ranks, parts);
    return parts;
  }
  uint64_t largestPart(const Prepared& p, std::vector<Part> parts,
                       const PartitionerOptions& o) const override {
    if (parts.size() > 1) {
      // One rank per part here (masks only count copies: one bit each).
      const size_t n = parts.size();  // balancing may empty (drop) parts
      balanceByBytes(p.units, p.inputBytes, int(n), parts);
      std::vector<RankSet> oneRank(parts.size(), RankSet::single(0));
      std::vector<RankSet> owners(p.units.units.size());
      replicateLargeUnits(p.units, parts, oneRank, owners, replicationBudget(o, p.inputBytes),
                          uint64_t(kBestMaxPart * double(p.inputBytes) / double(n)));
    }
    return SplitLoopPartitioner::largestPart(p, std::move(parts), o);
  }
  double replicationCap(const PartitionerOptions&) const override { return kBestMaxPart; }
};

class RayGuided final : public SplitLoopPartitioner {
 public:
  std::string_view name() const override { return "ray-guided"; }
  std::string_view summary() const override {
    return "as best, but each split takes, among balanced ones, the one a sample of rays "
           "crosses least";
  }
  bool cutsMeshes() const override { return true; }
  bool tracesRays() const override { return true; }
  int defaultInstanceBoxes() const override { return kShapeBoxesBySize; }
  std::vector<std::string_view> settings() const override {
    return {"keep-objects-whole", "replication-budget", "mesh-proxies",
            "instance-proxies",   "max-part",           "ray-paths"};
  }
  Partition partition(Scene& scene, int ranks, const PartitionerOptions& o,
                      PartitionStats& s) const override {
    if (o.raySample) return SplitLoopPartitioner::partition(scene, ranks, o, s);
    // The sample is traced through the scene as given, before it is rewritten.
    PartitionerOptions sampled = o;
    RaySamplerOptions r;
    r.seed = o.seed;
    r.paths = o.rayPaths;
    sampled.raySample = std::make_shared<const RaySample>(sampleSceneRays(scene, r));
    return SplitLoopPartitioner::partition(scene, ranks, sampled, s);
  }

 protected:
  ProxyKind proxyKind() const override { return ProxyKind::Braided; }
  std::vector<Part> split(const Prepared& p, int ranks, const PartitionerOptions& o,
                          PartitionStats& s) const override {
    // Splits are weighed with one box per instance whatever the proxies:
    // the parts are those of one box per instance, and braided proxies only
    // tighten them (docs/partitioning.md).
    const RayIncidence incidence =
        rayIncidence(unitProxyBoxes(*p.scene, p.units, o.meshProxies, 1), *o.raySample);
    RayGuidedSplitter splitter(p.units, incidence, ranks, o.maxPart);
    std::vector<Part> parts = runSplitLoop(splitter, ranks);
    refinePartsByRays(p.units, incidence, parts,
                      (o.maxPart - kRayGuidedRefineMargin) * double(p.inputBytes) / double(ranks));
    s.sampledRays = o.raySample->rays.size();
    s.sampledRaysAcrossUnits = incidence.rays();
    s.separatedRays = estimatedForwards(incidence, parts, p.units.units.size());
    s.sampleSeconds = o.raySample->seconds;
    return parts;
  }
  double replicationCap(const PartitionerOptions& o) const override {
    return o.maxPart + kRayGuidedReplicationMargin;
  }
};

// The test partitioners' stats (every instance a unit, every rank a part)
// and merged proxies, around the partition they dealt.
Partition byInstance(const Scene& scene, int ranks, Partition partition,
                     const PartitionerOptions& o, PartitionStats& s) {
  s.inputBytes = summarize(scene).memory.total();
  s.parts = ranks;
  s.units = scene.instances.size();
  mergePartitionProxies(partition, o, s);
  return partition;
}

class RoundRobin final : public Partitioner {
 public:
  std::string_view name() const override { return "round-robin"; }
  std::string_view summary() const override { return "instances dealt in turn (tests)"; }
  std::vector<std::string_view> settings() const override { return {}; }
  Partition partition(Scene& scene, int ranks, const PartitionerOptions& o,
                      PartitionStats& s) const override {
    return byInstance(scene, ranks, roundRobinPartition(scene, ranks), o, s);
  }
};

class Random final : public Partitioner {
 public:
  std::string_view name() const override { return "random"; }
  std::string_view summary() const override {
    return "random copies and overlapping proxies (tests)";
  }
  std::vector<std::string_view> settings() const override { return {}; }
  Partition partition(Scene& scene, int ranks, const PartitionerOptions& o,
                      PartitionStats& s) const override {
    return byInstance(scene, ranks, randomPartition(scene, ranks, o.seed), o, s);
  }
};

const SpatialSimple kSpatialSimple;
const SpatialSah kSpatialSah;
const ObjectNaive kObjectNaive;
const ObjectProxies kObjectProxies;
const BvhStyle kBvhStyle;
const Best kBest;
const RayGuided kRayGuided;
const RoundRobin kRoundRobin;
const Random kRandom;

}  // namespace

const std::vector<const Partitioner*>& partitioners() {
  static const std::vector<const Partitioner*> all = {&kSpatialSimple, &kSpatialSah, &kObjectNaive,
                                                      &kObjectProxies, &kBvhStyle,   &kBest,
                                                      &kRayGuided,     &kRoundRobin, &kRandom};
  return all;
}

const Partitioner& bestPartitioner() {
  return kBest;
}

const Partitioner& defaultPartitioner(int ranks) {
  return ranks > 1 ? static_cast<const Partitioner&>(kBest) : kRoundRobin;
}

}  // namespace ferry
