// The ray-guided partitioner (`--partitioner ray-guided`): the paper's loop
// (split the costliest part in two until there are N) where each split
// weighs memory with the forwarding a sample of rays would cause. A ray whose
// passed units end up on k ranks is forwarded about k - 1 times, so a split
// is charged the sampled rays it separates, and among the candidate planes
// balanced enough (each side within beta = 0.5 x M^(1/ceil(log2 N)) of its
// parent's bytes, or within the final limit) the one separating the fewest
// is taken. M (--max-part, kRayGuidedDefaultMaxPart) makes the largest part
// about M x total / N at most. Each split, and after the last the N parts
// together, are refined (part_assignment.h). The sample is made from the
// scene alone, never from the views evaluated (partition/ray_sampler.h).
// docs/partitioning.md, "The ray-guided partitioner".
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "partition/object_partitioner.h"
#include "partition/part_assignment.h"
#include "partition/proxies.h"
#include "partition/ray_sample.h"
#include "partition/split_loop.h"

namespace ferry {

// The units each sampled ray passes (one of their proxy boxes overlaps its
// segment: the boxes the partition's proxies will have, so the estimate
// counts what the forwarding operator will do): the hypergraph the parts are
// refined on, rows of unit ids. Rays through fewer than two units are left
// out (no partition separates them).
using RayIncidence = Hypergraph;
RayIncidence rayIncidence(const std::vector<UnitBox>& boxes, const RaySample& sample);

// The largest part the splits aim at by default, times total / N.
constexpr double kRayGuidedDefaultMaxPart = 1.25;

class RayGuidedSplitter final : public PartSplitter {
 public:
  RayGuidedSplitter(const UnitSet& units, const RayIncidence& incidence, int ranks,
                    double maxPart = kRayGuidedDefaultMaxPart);
  bool split(const Part& part, Part& left, Part& right) override;

  double balance() const { return beta_; }

 private:
  const RayIncidence& incidence_;
  double beta_;
  double finalLimit_;             // bytes: (maxPart - kRayGuidedRefineMargin) x total / N
  CentroidSplitter fallback_;     // a part no candidate plane splits: halved by count
  std::vector<int32_t> localOf_;  // unit -> index in the part being split, or -1
};

// After the splits: the parts refined together (part_assignment.h), every
// part brought within `limit` bytes where moves can, and units moved to
// parts their rays already touch where that lowers the estimate (with no
// rays, as `best` calls it: balanced by bytes alone). A part left empty is
// dropped: its rank gets a copy of the costliest part (assignRanks). Skipped
// above kMaxRefinedParts parts (it keeps a counter per ray and part).
constexpr size_t kMaxRefinedParts = 256;
// The parts are refined to (the largest part asked for - this) x total / N:
// 1.2 by default (replication adds up to its budget / N on top).
constexpr double kRayGuidedRefineMargin = 0.05;
// `best`'s replication may then fill a part up to (the largest part asked
// for + this) x total / N: 1.3 by default.
constexpr double kRayGuidedReplicationMargin = 0.05;
void refinePartsByRays(const UnitSet& units, const RayIncidence& incidence,
                       std::vector<Part>& parts, double limit);

// The sample's estimate of the forwarding: sum over rays of the parts the
// ray's units lie in, less one.
uint64_t estimatedForwards(const RayIncidence& incidence, const std::vector<Part>& parts,
                           size_t unitCount);

}  // namespace ferry
