// Partitioners: who owns which instances, and the proxies every rank keeps
// of what others own. Each partitioner is an object in the registry
// (partitioners(), partitioners.cpp) that names itself and the settings it
// reads; all are deterministic, so every rank computing the partition of the
// same scene gets the same answer. docs/partitioning.md describes each.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <variant>
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
// splits, and its replication fills none above kBestMaxPart x.
constexpr double kBestFinalBalance = 1.2;
constexpr double kBestMaxPart = 1.25;

class Partitioner;

// Which partitioner, and every setting a partitioner may read
// (partitionerSettings() says which reads what, with its help and range).
struct PartitionerOptions {
  const Partitioner* partitioner = nullptr;  // nullptr: bestPartitioner()
  // Keep non-instanced content whole, as one unit; false: each mesh of a
  // non-instanced object is its own unit (Zellmann et al.).
  bool keepObjectsWhole = false;
  double replicationBudget = 0.05;  // copies may add this fraction of the input's bytes
  int meshProxies = 64;             // boxes per non-instanced mesh (braiding)
  // Boxes per instance of an instanced object, per mesh of the object (1:
  // the object's box); 0: the partitioner's default (instanceProxiesFor).
  int instanceProxies = 0;
  // Proxies are merged down to this many (proxy_merge.h); 0: no limit.
  uint64_t maxProxies = kDefaultMaxProxies;
  uint64_t maxPieceBytes = 0;  // meshes above this are cut (0: input bytes / kBestPiecesPerScene)
  uint32_t seed = 1;           // random choices and ray samples
  // A ray sample to weigh splits with; none: a partitioner that traces
  // makes its own (rayPaths paths) from the scene as given.
  std::shared_ptr<const RaySample> raySample;
  uint64_t rayPaths = 65536;
  double maxPart = 1.25;  // the largest part aimed at, times total / N

  const Partitioner& chosen() const;
};

// A setting of PartitionerOptions as the command line shows it (--NAME) and
// checks it.
struct PartitionerSetting {
  using Field = std::variant<bool PartitionerOptions::*, int PartitionerOptions::*,
                             double PartitionerOptions::*, uint64_t PartitionerOptions::*>;
  std::string_view name;  // e.g. "mesh-proxies"
  std::string_view help;
  Field field;
  double min = 0, max = 0;  // the accepted range (not for bool)
  std::string range;        // the range in words; empty: "min to max"

  std::string rangeText() const;
  std::string valueText(const PartitionerOptions& options) const;
};
const std::vector<PartitionerSetting>& partitionerSettings();
// The first setting outside its range, or nullptr.
const PartitionerSetting* firstSettingOutOfRange(const PartitionerOptions& options);
// Throws InputError naming the first setting outside its range.
void checkPartitionerOptions(const PartitionerOptions& options);

struct PartitionStats;

// A partitioner (the paper's six, Ferry's two, and two that test the
// distributed layer): its name, what it reads, and how it partitions.
// Partitioners are stateless singletons, found in partitioners().
class Partitioner {
 public:
  virtual ~Partitioner() = default;
  virtual std::string_view name() const = 0;
  virtual std::string_view summary() const = 0;  // a line for the help
  // The settings (partitionerSettings() names) it reads beyond max-proxies.
  virtual std::vector<std::string_view> settings() const = 0;
  bool reads(std::string_view setting) const;
  virtual bool fromThePaper() const { return false; }
  // Cuts large meshes into pieces (rewrites the scene even when objects are kept whole).
  virtual bool cutsMeshes() const { return false; }
  // Traces a ray sample through the whole scene, which must be in memory.
  virtual bool tracesRays() const { return false; }
  // Boxes per instanced mesh when the instance-proxies setting is 0.
  virtual int defaultInstanceBoxes() const { return 1; }

  // Partitions `scene` over `ranks`, rewriting the scene where it splits
  // content (same image); fills what `stats` says of the partitioner's own
  // steps, and merges its proxies down to options.maxProxies.
  virtual Partition partition(Scene& scene, int ranks, const PartitionerOptions& options,
                              PartitionStats& stats) const = 0;
  // The largest part's bytes for 1..maxRanks (the paper's Figure 4); only
  // the paper's partitioners answer, others throw InputError.
  virtual std::vector<uint64_t> maxPartBytesCurve(Scene& scene, const PartitionerOptions& options,
                                                  int maxRanks) const;
};

// Every partitioner, in the order the help lists them; the paper's six first.
const std::vector<const Partitioner*>& partitioners();
// By name; throws InputError naming the accepted ones.
const Partitioner& partitionerNamed(std::string_view name);
const Partitioner& bestPartitioner();
// The registry's names, and those of the paper's six, in its order.
const std::vector<std::string>& partitionerNames();
const std::vector<std::string>& paperPartitionerNames();
// What a session uses when none is chosen: best on more than one rank,
// round-robin (which splits nothing) on one.
const Partitioner& defaultPartitioner(int ranks);

// The boxes per instanced mesh each instance gets: the instance-proxies
// setting, else the partitioner's default (kShapeBoxesBySize: by size, see
// proxies.h). Above 1 they are instanced proxies, held once per object in
// object space (distributed/proxy_bvh.h); when the instances alone reach
// max-proxies they are world boxes instead, at most kMaxWorldInstanceBoxes
// per mesh, and the default gives the object's box.
constexpr int kMaxInstanceProxies = kMaxShapeBoxesPerMesh;
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

// Partitions `scene` over `ranks` (1..kMaxRanks) with options.chosen(). The
// paper's partitioners and Ferry's first rewrite the scene in place with
// splitForPartitioning (same image); the partition refers to the rewritten
// scene.
Partition partitionScene(Scene& scene, int ranks, const PartitionerOptions& options,
                         PartitionStats* stats = nullptr);

// For reports (the paper's Figure 4): the largest part's bytes for 1, 2, ...,
// maxRanks ranks, from one run of the split loop (the loop's states for
// smaller counts are its first steps). Rewrites `scene` like partitionScene.
// One of the six only.
std::vector<uint64_t> maxPartBytesCurve(Scene& scene, const PartitionerOptions& options,
                                        int maxRanks);

// Merges `partition`'s proxies down to options.maxProxies, recording the
// count before and after in `stats` (for partitioners that do not merge as
// they make them).
void mergePartitionProxies(Partition& partition, const PartitionerOptions& options,
                           PartitionStats& stats);

}  // namespace ferry
