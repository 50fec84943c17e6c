// Ray traversal across ranks (paper, Sections 3 and 5.2), in one of two
// exchanges:
//
// - bulk (the paper's): a whole-image wavefront per bounce. Per round: trace
//   the rays that are here on the local geometry, decide each ray's next rank
//   with the forwarding operator, compact by destination, exchange counts then
//   rays (all-to-all, all-to-all-v), until no ray moves on any rank. What is
//   left on each rank is what it shades (traverse()).
// - overlapped: the traversal runs the whole sample (runSample(),
//   overlapped_exchange.cpp): camera paths in chunks, rays sent in
//   non-blocking messages as soon as a batch is traced, no collective per
//   round (docs/data-parallel.md).
// The forwarding operator, and so every ray's path through the ranks, is the
// same in both; so is the image (the frame buffer sums in fixed point).
#pragma once

#include <string>
#include <vector>

#include "comm/communicator.h"
#include "distributed/forwarding.h"
#include "distributed/proxy_bvh.h"
#include "partition/partition.h"
#include "render/ray_traversal.h"

namespace ferry {

enum class ExchangeMode : uint8_t {
  Auto,        // overlapped where it is built (proxies, ring), else bulk (broadcast)
  Overlapped,  // rays sent as soon as traced, non-blocking; chunks overlap
  Bulk,        // the paper's: a collective exchange per round of a whole-image wavefront
};
ExchangeMode parseExchangeMode(const std::string& name);  // --exchange; throws InputError
std::string toString(ExchangeMode mode);
// What `mode` is with `forwarding` (Auto resolved); throws InputError for
// overlapped broadcast (broadcast's three-step replies are built on rounds).
ExchangeMode resolveExchangeMode(ExchangeMode mode, ForwardingMode forwarding);

template <typename Path>
class DistributedTraversal final : public RayTraversal<Path> {
 public:
  // `chunkPixels`: overlapped, camera paths a rank starts at once, and the
  // largest batch it traces at once (any value gives the same image).
  // `proxies`: the partition's proxies, built with this rank as the own rank
  // (the caller keeps them, built once for every run); `partition`: for the
  // instances' owners.
  DistributedTraversal(const Communicator& comm, const TraceBackend& geometry,
                       const Partition& partition, const ProxyBvh& proxies, ForwardingMode mode,
                       ExchangeMode exchange = ExchangeMode::Auto, uint32_t chunkPixels = 8192);
  bool runsSamples() const override { return exchange_ == ExchangeMode::Overlapped; }
  void runSample(uint32_t sampleIndex, const PixelSet& set, SampleShading<Path>& shading,
                 FrameStats& stats) override;
  void primaryPixels(const PixelSet& set, const CameraRays& cameraRays,
                     std::vector<uint32_t>& pixels, FrameStats& stats) override;
  void traverse(RayQueues<Path>& rays, std::vector<TraceHit>& pathHits, ExchangeCounters& exchange,
                FrameStats& stats) override;
  bool anyRaysLeft(size_t localRays) override { return comm_.sum(uint64_t(localRays)) > 0; }
  bool sumOverRanks(std::vector<int64_t>& values) override {
    // Two's complement: summing as unsigned gives the signed sums.
    std::vector<uint64_t> words(values.begin(), values.end());
    words = comm_.sum(std::span<const uint64_t>(words));
    for (size_t i = 0; i < values.size(); ++i) values[i] = int64_t(words[i]);
    return comm_.isRoot();
  }

  // Rays that arrived for tracing on a rank they had already visited (must
  // stay 0). Replay layout: rays arriving back at their generating rank, or
  // whose replayed walk does not lead to this rank.
  uint64_t revisits() const { return revisits_; }
  // Rays received, counted on the receiving side (an independent count of forwards).
  uint64_t received() const { return received_; }

 private:
  struct ViewOwnership;
  // The rank whose camera path `pixel` is: the owner of the closest proxy
  // (of a replicated one, the owner that reaches farthest); `queries`: the
  // proxy queries it took.
  int primaryOwner(uint32_t pixel, const TraceRay& ray, uint32_t& queries) const;
  // ownerOf(pixel, queries, closest) for each of `pixels`, in parallel;
  // counts the queries (`closest` of them closest-proxy ones, the rest
  // weighing replicas).
  template <typename OwnerOf>
  std::vector<int32_t> owners(const std::vector<uint32_t>& pixels, FrameStats& stats,
                              const OwnerOf& ownerOf) const;
  // Sends each of `pixels` to rank owner[i] (collective); returns the pixels
  // this rank was sent, in increasing order.
  std::vector<uint32_t> sendToOwners(const std::vector<uint32_t>& pixels,
                                     const std::vector<int32_t>& owner, FrameStats& stats) const;
  // Both take the wavefront as it travels (both kinds in one queue) and add
  // the rays left here to shade to `ready`, by kind (readyHits: per path).
  void traverseForwarding(PathQueue<Path> moving, RayQueues<Path>& ready,
                          std::vector<TraceHit>& readyHits, ExchangeCounters& exchange,
                          FrameStats& stats);
  void traverseBroadcast(PathQueue<Path> rays, RayQueues<Path>& ready,
                         std::vector<TraceHit>& readyHits, ExchangeCounters& exchange,
                         FrameStats& stats);
  // Sends each ray to destination[i] (this rank's rays are not in the list);
  // returns what this rank received, in rank order.
  PathQueue<Path> exchange(const PathQueue<Path>& rays, const std::vector<int>& destination,
                           ExchangeCounters& counters, FrameStats& stats);
  // Each ray's next step after its trace here (decisionToDestination's
  // values), into `destination`; `visited` (replay layout, proxies): each
  // ray's visited set. Counts proxy queries.
  // `cameraClearance`: for a batch of a sample's camera paths traced where
  // they were made, sampleView_ (camera rays nearer than their pixel's
  // clearance are decided without a query).
  void decide(PathQueue<Path>& rays, const std::vector<RankSet>& visited,
              std::vector<int>& destination, FrameStats& stats,
              const ViewOwnership* cameraClearance = nullptr) const;
  // With `hits`: resized to rays.size(), the hits that set a ray's tmax here.
  void trace(PathQueue<Path>& rays, FrameStats& stats, std::vector<TraceHit>* hits = nullptr);
  // trace() for rays that arrived to be traversed here, counting in
  // `counters` those that find nothing here (visitsWithoutHit).
  void traceArrivals(PathQueue<Path>& rays, std::vector<TraceHit>& hits, ExchangeCounters& counters,
                     FrameStats& stats);
  // Replay layout, proxies mode: the visited set of each ray that arrived
  // here, recomputed from its generating rank (this rank included).
  std::vector<RankSet> replayArrivals(const PathQueue<Path>& rays, FrameStats& stats);
  // runSample's state and steps (overlapped_exchange.cpp).
  class OverlappedSample;

  const Communicator& comm_;
  const TraceBackend& geometry_;
  ForwardingMode mode_;
  ExchangeMode exchange_;
  uint32_t chunkPixels_;
  const ProxyBvh& proxies_;
  // Camera-path owners for a pinhole view and pixel range: whether a sample
  // of it was decided pixel by pixel, and once decided, the pixels this rank
  // starts in every sample and those dealt to it that are decided sample by
  // sample (their corners and centre have different owners).
  // Once decided, `clearance[pixel - first]` for each fixed pixel: how far
  // its camera rays may hit here before another rank's proxy could be nearer
  // (ProxyBvh::coneClearance less a rounding margin; 0 for other pixels), so
  // that the forwarding decision after the camera ray's trace needs no query.
  struct ViewOwnership {
    uint64_t view = 0;
    PixelSet set;  // clearance covers [set.first, set.last) (0 outside the set)
    bool seen = false, decided = false;
    std::vector<uint32_t> fixed, varying;
    std::vector<float> clearance;
  };
  // The clearance of this rank's fixed pixels of `view`, into view.clearance.
  void computeClearance(ViewOwnership& view, const CameraRays& cameraRays) const;
  static constexpr int32_t kVariesBySample = -1;
  static constexpr size_t kMaxOwnershipRanges = 256;
  std::vector<ViewOwnership> viewOwnership_;  // the current view's, per pixel set
  // The view and range of the sample primaryPixels last decided, when its
  // pixels were fixed (its clearance applies to the sample's camera rays).
  const ViewOwnership* sampleView_ = nullptr;
  std::vector<uint64_t>
      instanceOwners_;  // mask layouts: owner mask per instance (empty for replay)
  // Overlapped: rays of a later sample that arrived before this rank saw the
  // end of the current one (a rank that saw it first may already be sending
  // the next sample's rays: ring forwarding has no collective in between).
  struct EarlyRays {
    uint32_t sample, bounce;
    PathQueue<Path> rays;
  };
  std::vector<EarlyRays> early_;
  bool firstExchange_ = true;
  uint64_t revisits_ = 0;
  uint64_t received_ = 0;
};

}  // namespace ferry
