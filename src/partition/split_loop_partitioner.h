// The steps the paper's partitioners and Ferry's share: rewrite the scene
// (objects broken into meshes, large meshes cut), make units, split them
// into parts with a PartSplitter (split_loop.h), give parts ranks, copy
// large cheap units where asked, make proxies. A partitioner overrides the
// steps it does its own way.
#pragma once

#include <memory>
#include <vector>

#include "partition/partitioner.h"
#include "partition/split_loop.h"
#include "partition/units.h"

namespace ferry {

class SplitLoopPartitioner : public Partitioner {
 public:
  Partition partition(Scene& scene, int ranks, const PartitionerOptions& options,
                      PartitionStats& stats) const override;
  std::vector<uint64_t> maxPartBytesCurve(Scene& scene, const PartitionerOptions& options,
                                          int maxRanks) const override;

 protected:
  // The scene rewritten for this partitioner, and its units.
  struct Prepared {
    const Scene* scene = nullptr;  // rewritten
    uint64_t inputBytes = 0;
    SceneSplitReport split;
    UnitSet units;
  };
  enum class ProxyKind {
    Domains,    // the parts' domains (spatial partitioners)
    UnitBoxes,  // one box per unit
    Braided,    // boxes by BVH build steps per mesh, instanced proxies per instance
    Instances,  // one box per instance or non-instanced mesh
  };

  virtual ProxyKind proxyKind() const = 0;
  virtual UnitGrouping grouping() const { return UnitGrouping::Instances; }
  virtual std::unique_ptr<PartSplitter> splitter(const UnitSet& units) const;
  // The parts for `ranks` ranks; by default the split loop over splitter().
  virtual std::vector<Part> split(const Prepared& prepared, int ranks,
                                  const PartitionerOptions& options, PartitionStats& stats) const;
  // The largest part of `parts` as the max-part curve counts it.
  virtual uint64_t largestPart(const Prepared& prepared, std::vector<Part> parts,
                               const PartitionerOptions& options) const;
  // Copies of large cheap units may fill parts up to this x an even share;
  // 0: no copies.
  virtual double replicationCap(const PartitionerOptions&) const { return 0; }

 private:
  Prepared prepare(Scene& scene, const PartitionerOptions& options) const;
  void makeProxies(const Scene& scene, const Prepared& prepared, const std::vector<Part>& parts,
                   const std::vector<RankSet>& partRanks, const std::vector<RankSet>& owners,
                   const PartitionerOptions& options, Partition& partition,
                   PartitionStats& stats) const;
};

// The copies' byte budget: the replication-budget setting x the input's bytes.
uint64_t replicationBudget(const PartitionerOptions& options, uint64_t inputBytes);

}  // namespace ferry
