// Partitioners by name: the paper's six (Section 4) and the two that test the
// distributed layer. Every one of the six runs the same loop (split_loop.h)
// on units (units.h) and differs in how it splits and what proxies it makes:
//
//   spatial-simple  domains split at the spatial median of the longest axis;
//                   straddling content on both sides; proxies: the domains
//   spatial-sah     the same with the best of 3 x 7 planes by splitCost()
//   object-naive    whole objects (all instances on one rank) by their box
//                   centres, 3 x 7 planes; proxies: the objects' boxes
//   object-proxies  the same parts; proxies: one per instance, and 64 per
//                   non-instanced mesh by BVH build steps (braiding)
//   bvh-style       instances as units (objects replicated where instances
//                   land); one proxy per instance or non-instanced mesh
//   best            large meshes first cut into tight pieces, then as
//                   bvh-style, then parts over 1.2x an even share give units
//                   to lighter ones, then spatially large but cheap content
//                   replicated on every rank up to a budget (default 5%);
//                   proxies: one per instance, and 64 per mesh piece by
//                   braiding, as object-proxies (Ferry's, beyond the paper)
//   ray-guided      as best, but each split takes, among balanced ones, the
//                   one a sample of rays crosses least (ray_guided_partitioner.h)
//   round-robin     instances dealt in turn (tests)
//   random          random replication and overlapping proxies (tests)
//
// All are deterministic: every rank computing the same partition of the
// same scene gets the same answer.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "partition/partition.h"
#include "partition/proxies.h"
#include "partition/proxy_merge.h"
#include "partition/ray_sample.h"
#include "partition/scene_split.h"

namespace ferry {

struct Scene;

// `best` cuts meshes costing more than the input's bytes / this.
constexpr int kBestPiecesPerScene = 256;
// `best` brings its parts within kBestFinalBalance x an even share after the
// splits, and its replication fills none above kBestMaxPart x (issue 16).
constexpr double kBestFinalBalance = 1.2;
constexpr double kBestMaxPart = 1.25;

struct PartitionerOptions {
  std::string name = "best";
  // Break non-instanced objects into their meshes (Zellmann et al.); false:
  // keep all non-instanced content whole, as one unit.
  bool breakObjects = true;
  double replicationBudget = 0.05;  // best: copies may add this fraction of the input's bytes
  int meshProxies = 64;  // object-proxies, best, ray-guided: boxes per non-instanced mesh
  // object-proxies, best, ray-guided: boxes per instance of an instanced
  // object, per mesh of the object (1: the object's box). More cut forwards
  // and cost every rank proxy memory (docs/partitioning.md). 0: the
  // partitioner's default (instanceProxiesFor), by size for best and
  // ray-guided.
  int instanceProxies = 0;
  // Proxies are merged down to this many (proxy_merge.h); 0: no limit.
  uint64_t maxProxies = kDefaultMaxProxies;
  uint64_t maxPieceBytes = 0;  // best: cut meshes above this (0: input bytes / kBestPiecesPerScene)
  uint32_t seed = 1;           // random; ray-guided: its sample
  // ray-guided: the rays it weighs splits with (partition/ray_sampler.h makes
  // them: withRaySample), and how many paths that sample has.
  std::shared_ptr<const RaySample> raySample;
  uint64_t rayPaths = 65536;
  // ray-guided: the largest part it aims at, times total / N (--max-part).
  double maxPart = 1.25;  // kRayGuidedDefaultMaxPart
};

// The boxes per instanced mesh a partitioner gives each instance: the
// option, or by default kShapeBoxesBySize for best and ray-guided (one box
// per 4 triangles of each mesh, at most 1024: partition/proxies.h) and 1
// for the others (object-proxies: the paper's one box per instance).
// Above 1 they are instanced proxies: the boxes are held once per object,
// in object space, under a small tree of their own (distributed/proxy_bvh.h), so
// fine shapes cost about 30 bytes per box and little query time. By size
// they forward 10-22 % fewer rays than 64 per mesh did
// (docs/partitioning.md, "Shapes by size"). When the instances alone would
// reach --max-proxies they become world boxes, k per mesh per instance
// before merging, which is allowed up to kMaxWorldInstanceBoxes; the
// default gives the object's box then, which keeps partitioning linear in
// the instances (docs/partitioning.md, "At scale").
constexpr int kMaxInstanceProxies = kMaxShapeBoxesPerMesh;  // --instance-proxies N: at most
constexpr int kMaxWorldInstanceBoxes = 64;
int instanceProxiesFor(const PartitionerOptions& options);

struct PartitionStats {
  std::string partitioner;
  int ranks = 0;
  int parts = 0;                 // distinct parts; fewer than ranks when units ran out (copies)
  uint64_t inputBytes = 0;       // memory estimate of the scene as given
  uint64_t replicatedBytes = 0;  // best: what its copies added, over all ranks
  uint64_t replicatedUnits = 0;
  std::vector<uint64_t> rankBytes;  // memory estimate of what each rank holds
  uint64_t proxies = 0;
  uint64_t unmergedProxies = 0;  // before mergeProxies (equal to proxies when none were merged)
  uint64_t units = 0;
  SceneSplitReport split;
  double seconds = 0;
  // ray-guided: its sample (rays, and those passing two or more units), and
  // how many of those its splits separate (its estimate of the forwarding).
  uint64_t sampledRays = 0;
  uint64_t sampledRaysAcrossUnits = 0;
  uint64_t separatedRays = 0;
  double sampleSeconds = 0;

  uint64_t maxRankBytes() const;
};

// Every name `--partitioner` accepts, and the paper's six among them.
const std::vector<std::string>& partitionerNames();
const std::vector<std::string>& paperPartitionerNames();
// Throws InputError naming the accepted ones.
void checkPartitionerName(const std::string& name);

// The partitioners as a choice a command line makes once (in partitionerNames() order).
enum class PartitionerKind {
  SpatialSimple,
  SpatialSah,
  ObjectNaive,
  ObjectProxies,
  BvhStyle,
  Best,
  RayGuided,
  RoundRobin,
  Random
};
// By name; throws InputError naming the accepted ones (as checkPartitionerName).
PartitionerKind parsePartitioner(const std::string& name);
// The name (PartitionerOptions::name, the stats).
std::string toString(PartitionerKind kind);

// Partitions `scene` over `ranks` (1..kMaxRanks). The six paper partitioners first
// rewrite the scene in place with splitForPartitioning (same image); the
// partition refers to the rewritten scene.
Partition partitionScene(Scene& scene, int ranks, const PartitionerOptions& options,
                         PartitionStats* stats = nullptr);

// For reports (the paper's Figure 4): the largest part's bytes for 1, 2, ...,
// maxRanks ranks, from one run of the split loop (the loop's states for
// smaller counts are its first steps). Rewrites `scene` like partitionScene.
// One of the six only.
std::vector<uint64_t> maxPartBytesCurve(Scene& scene, const PartitionerOptions& options,
                                        int maxRanks);

}  // namespace ferry
