// Counters and timings of a render, kept by the code that does the work (not
// estimated afterwards). Every field is a sum, so ranks' stats add up.
//
// Each counter is named once, in the tables below the structs (its JSON key
// and member): adding, merging, the JSON and the sum over ranks walk them, so
// a new counter is one member and one table line.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace ferry {

// One wavefront's distributed traversal (the dist layer fills these).
struct ExchangeCounters {
  uint64_t raysForwarded = 0;  // rays sent to another rank
  // Of raysForwarded, by kind (the rest are camera rays and continuations
  // still being traversed, which exchange_per_bounce tells apart):
  uint64_t shadowRaysForwarded = 0;  // shadow rays
  uint64_t forwardedToShade = 0;     // traversal done: sent to a hit owner only to be shaded
  // Counted where rays arrive: rays sent to be traversed that found nothing
  // on the rank they were sent to (no hit closer than the one they carried;
  // a shadow ray, no occluder). What the proxies' looseness costs: with
  // proxies as tight as the geometry, only the forwards of rays that find
  // something (and no ray sent back to be shaded) would be left.
  uint64_t visitsWithoutHit = 0;
  uint64_t bytesSent = 0;  // ray payload bytes sent to other ranks
  uint64_t rounds = 0;     // bulk exchange: rounds until no ray moved
  uint64_t messages = 0;   // overlapped exchange: ray messages sent
  ExchangeCounters& operator+=(const ExchangeCounters& o);
  // Counts `rays` as sent (rays, bytes of `rayBytes` each, and their kinds).
  template <typename Ray>
  void countSent(const Ray* rays, size_t count, size_t rayBytes) {
    raysForwarded += count;
    bytesSent += count * rayBytes;
    for (size_t i = 0; i < count; ++i) {
      shadowRaysForwarded += rays[i].isShadow();
      forwardedToShade += !rays[i].isShadow() && rays[i].isTraversed();
    }
  }
};

// Seconds per stage: summed over ranks when merged; on one rank the chunks
// run in parallel, so there they are summed over threads too.
struct StageTimes {
  double generate = 0;   // the frame's set-up (its frame buffer), camera rays, and their
                         // owners' proxy queries (the owners' collectives: wait, then exchange)
  double trace = 0;      // local traces inside traversal
  double exchange = 0;   // forwarding decisions, compaction, MPI
  double shade = 0;      // shadow-ray contributions, re-trace, BSDF and light sampling, spawning
  double wait = 0;       // overlapped exchange: idle, waiting for rays or for the end of the sample
  double composite = 0;  // merging frame buffers
  StageTimes& operator+=(const StageTimes& o);
  double total() const { return generate + trace + exchange + shade + wait + composite; }
};

struct FrameStats {
  int frame = 0;
  double seconds = 0;                // wall clock of the frame (max over ranks when merged)
  double cpuSeconds = 0;             // CPU time of the frame, every thread (summed when merged)
  double busiestRankCpuSeconds = 0;  // the largest one rank's cpuSeconds (max over ranks,
                                     // summed over frames): with cpuSeconds, the imbalance
  uint64_t cameraPaths = 0;          // primary rays generated (kept by this rank)
  uint64_t lightPaths = 0;           // light paths started at emitters (render/path_shading.h)
  uint64_t continuationRays = 0;
  uint64_t shadowRays = 0;
  uint64_t closestTraces = 0;    // local closest-hit traces (a forwarded ray counts per rank)
  uint64_t occlusionTraces = 0;  // local shadow-ray traces
  uint64_t retraces = 0;         // shading re-traces
  uint64_t retraceMisses = 0;    // re-traces that did not find the hit again (should be 0)
  uint64_t proxyQueries = 0;     // proxy-BVH queries: camera-ray ownership and forwarding decisions
  uint64_t replayQueries = 0;    // replay layout: proxy queries spent recomputing visited sets
  uint64_t primaryQueries = 0;   // of proxyQueries: deciding which rank generates a camera path
                                 // (a closest proxy: one per camera path in a view's first
                                 // sample, five per pixel once in its second, then one per camera
                                 // path of pixels whose corners' owners differ)
  uint64_t replicaQueries = 0;   // of proxyQueries: weighing a replicated proxy's owners (one per
                                 // owner; distributed/forwarding.h, reachingOwners)
  uint64_t skippedQueries = 0;   // forwarding decisions made without a query: camera rays that
                                 // hit nearer than any other rank's proxy in their pixel
  uint64_t primaryBytesSent = 0;  // pixel ids sent to the ranks that generate their camera paths
  uint64_t terminationWaves = 0;  // overlapped exchange: non-blocking sums until a sample ended
  // Tracking through participating media (media/tracking.h): collisions that
  // scattered or absorbed, tentative ones that went on, majorant cells stepped.
  uint64_t mediumRealCollisions = 0;
  uint64_t mediumNullCollisions = 0;
  uint64_t mediumMajorantCells = 0;
  std::vector<ExchangeCounters> perBounce;
  StageTimes times;

  ExchangeCounters exchangeTotal() const;
  uint64_t raysTraced() const { return closestTraces + occlusionTraces + retraces; }
  // Adds another rank's counters (seconds: the maximum; CPU seconds: the sum).
  void merge(const FrameStats& other);
  nlohmann::json toJson() const;

  // Every counter as one array, in table order (kFrameCounters, then
  // kExchangeCounters of each bounce): what the ranks sum element-wise.
  std::vector<uint64_t> counterValues() const;
  // The inverse of counterValues(): perBounce gets as many bounces as `values` holds.
  void setCounterValues(std::span<const uint64_t> values);
  // The stage times in kStageTimes order, and back.
  std::vector<double> stageTimeValues() const;
  void setStageTimeValues(std::span<const double> values);
};

// A counter's JSON key (inside `group` when there is one) and its member.
template <typename Owner, typename Value>
struct StatsField {
  const char* group;  // nullptr: a key of the frame's own object
  const char* key;
  Value Owner::*member;
};

inline constexpr StatsField<FrameStats, uint64_t> kFrameCounters[] = {
    {nullptr, "camera_paths", &FrameStats::cameraPaths},
    {nullptr, "light_paths", &FrameStats::lightPaths},
    {nullptr, "continuation_rays", &FrameStats::continuationRays},
    {nullptr, "shadow_rays", &FrameStats::shadowRays},
    {"traces", "closest", &FrameStats::closestTraces},
    {"traces", "occlusion", &FrameStats::occlusionTraces},
    {"traces", "retrace", &FrameStats::retraces},
    {"traces", "retrace_misses", &FrameStats::retraceMisses},
    {"traces", "proxy_queries", &FrameStats::proxyQueries},
    {"traces", "replay_queries", &FrameStats::replayQueries},
    {"traces", "primary_queries", &FrameStats::primaryQueries},
    {"traces", "replica_queries", &FrameStats::replicaQueries},
    {"traces", "skipped_queries", &FrameStats::skippedQueries},
    {nullptr, "primary_bytes_sent", &FrameStats::primaryBytesSent},
    {nullptr, "termination_waves", &FrameStats::terminationWaves},
    {"media", "real_collisions", &FrameStats::mediumRealCollisions},
    {"media", "null_collisions", &FrameStats::mediumNullCollisions},
    {"media", "majorant_cells", &FrameStats::mediumMajorantCells},
};
// Per bounce under "exchange_per_bounce", and summed over bounces under "exchange".
inline constexpr StatsField<ExchangeCounters, uint64_t> kExchangeCounters[] = {
    {nullptr, "rays_forwarded", &ExchangeCounters::raysForwarded},
    {nullptr, "shadow_rays_forwarded", &ExchangeCounters::shadowRaysForwarded},
    {nullptr, "forwarded_to_shade", &ExchangeCounters::forwardedToShade},
    {nullptr, "visits_without_hit", &ExchangeCounters::visitsWithoutHit},
    {nullptr, "bytes_sent", &ExchangeCounters::bytesSent},
    {nullptr, "rounds", &ExchangeCounters::rounds},
    {nullptr, "messages", &ExchangeCounters::messages},
};
inline constexpr StatsField<StageTimes, double> kStageTimes[] = {
    {"stage_seconds", "generate", &StageTimes::generate},
    {"stage_seconds", "trace", &StageTimes::trace},
    {"stage_seconds", "exchange", &StageTimes::exchange},
    {"stage_seconds", "shade", &StageTimes::shade},
    {"stage_seconds", "wait", &StageTimes::wait},
    {"stage_seconds", "composite", &StageTimes::composite},
};

struct RenderStats {
  std::vector<FrameStats> frames;
  FrameStats total() const;
  nlohmann::json toJson() const;
  std::string summaryText(int ranks) const;
};

}  // namespace ferry
