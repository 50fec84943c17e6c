// The ray-guided partitioner (`--partitioner ray-guided`, issue 16): the
// paper's loop (split the costliest part in two until there are N) where
// each split weighs memory with the forwarding a sample of rays would cause.
//
// Forwarding, from the sample: a ray is sent to every rank owning a proxy it
// passes before its hit (each rank at most once), so a ray whose passed
// units -- every unit whose box its segment from origin to hit overlaps,
// which includes the unit it starts on and the one it hits -- end up on k
// ranks is forwarded about k - 1 times. In a binary split hierarchy those
// k - 1 are exactly the splits that put some of the ray's units on each
// side, so counting, for a candidate split, the sampled rays it separates
// (straddles) counts the forwards that split adds; the loop takes, among
// splits balanced enough, the one that separates the fewest.
//
// Balance: each side may hold at most `beta` of its parent's bytes, beta =
// 0.5 x M^(1/levels) with levels = ceil(log2 N) and M the largest part
// asked for (--max-part, default kRayGuidedDefaultMaxPart = 1.25): after the
// levels of splits N ranks need, the largest part holds at most M x total /
// N (the goal is 1.3; replication and shared meshes need the rest).
// A side within the final limit, (M - kRayGuidedRefineMargin) x total / N,
// is always balanced enough: shared content does not halve. When no
// candidate is balanced, the most balanced one is taken. A larger M trades
// memory for fewer forwarded rays.
//
// Each split is then refined (part_assignment.h): moves of units, of an
// object's instances and of the users of a shared mesh bring the sides
// within the limit and lower the rays separated. After the last split the
// N parts are refined together in the same way, with the final limit.
//
// Candidates: like `best` (object_partitioner.h), units sorted by their own
// box centre and by the centre of their object's instances, each along 3
// axes, cut at 17 byte quantiles (30% .. 70% of the part's bytes) and at 7
// equidistant planes. After the splits, `best`'s replication of large cheap
// units, and the proxies of `object-proxies`: one per instance of an
// instanced object, and 64 tight boxes per non-instanced mesh (braiding,
// `--mesh-proxies`), so that rays pass through the gaps of terrain pieces.
//
// The sample is made from the scene alone, never from the views evaluated:
// partition/ray_sampler.h.
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
// 1.2 by default (the goal is 1.3; replication adds up to its
// budget / N on top).
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
