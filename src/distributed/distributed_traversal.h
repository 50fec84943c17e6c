// Ray traversal across ranks (paper, Sections 3 and 5.2). Per round: trace
// the rays that are here on the local geometry, decide each ray's next rank
// with the forwarding operator, compact by destination, exchange counts then
// rays (all-to-all, all-to-all-v), until no ray moves on any rank. What is left
// on each rank is what it shades.
#pragma once

#include <vector>

#include "distributed/forwarding.h"
#include "mpi/communicator.h"
#include "partition/partition.h"
#include "render/ray_traversal.h"
#include "trace/proxy_bvh.h"

namespace ferry {

template <typename Path>
class DistributedTraversal final : public RayTraversal<Path> {
 public:
  DistributedTraversal(const Communicator& comm, const TraceBackend& geometry,
                       const Partition& partition, ForwardingMode mode);
  void primaryPixels(uint32_t first, uint32_t last, const CameraRayOf& cameraRay,
                     std::vector<uint32_t>& pixels, FrameStats& stats) override;
  void traverse(RayQueues<Path>& rays, std::vector<TraceHit>& pathHits, ExchangeCounters& exchange,
                FrameStats& stats) override;
  bool anyRaysLeft(size_t localRays) override { return comm_.sum(uint64_t(localRays)) > 0; }

  // Rays that arrived for tracing on a rank they had already visited (must
  // stay 0). Replay layout: rays arriving back at their generating rank, or
  // whose replayed walk does not lead to this rank.
  uint64_t revisits() const { return revisits_; }
  // Rays received, counted on the receiving side (an independent count of forwards).
  uint64_t received() const { return received_; }

 private:
  // The rank whose camera path `pixel` is: the owner of the closest proxy.
  int primaryOwner(uint32_t pixel, const TraceRay& ray) const;
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
  // With `hits`: resized to rays.size(), the hits that set a ray's tmax here.
  void trace(PathQueue<Path>& rays, FrameStats& stats, std::vector<TraceHit>* hits = nullptr);
  // Replay layout, proxies mode: the visited set of each ray that arrived
  // here, recomputed from its generating rank (this rank included).
  std::vector<RankSet> replayArrivals(const PathQueue<Path>& rays, FrameStats& stats);

  const Communicator& comm_;
  const TraceBackend& geometry_;
  ForwardingMode mode_;
  ProxyBvh proxies_;
  std::vector<uint64_t>
      instanceOwners_;  // mask layouts: owner mask per instance (empty for replay)
  bool firstExchange_ = true;
  uint64_t revisits_ = 0;
  uint64_t received_ = 0;
};

}  // namespace ferry
