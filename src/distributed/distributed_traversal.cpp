#include "distributed/distributed_traversal.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <unordered_map>

#include <fmt/format.h>

#include "core/clock.h"
#include "core/error.h"
#include "core/fault_injection.h"
#include "distributed/ray_routing.h"

namespace ferry {
namespace {

// Broadcast mode: what finds a reply's original among a rank's rays.
uint64_t replyKey(const PathCore& p) {
  return uint64_t(p.pixel()) * 4 + (p.isShadow() ? 1 : 0) + (p.has(kPathLight) ? 2 : 0);
}

}  // namespace

ExchangeMode parseExchangeMode(const std::string& name) {
  if (name == "auto") return ExchangeMode::Auto;
  if (name == "overlapped") return ExchangeMode::Overlapped;
  if (name == "bulk") return ExchangeMode::Bulk;
  throw InputError(fmt::format("exchange '{}': expected auto, overlapped or bulk", name));
}

std::string toString(ExchangeMode mode) {
  switch (mode) {
    case ExchangeMode::Auto:
      return "auto";
    case ExchangeMode::Overlapped:
      return "overlapped";
    case ExchangeMode::Bulk:
      return "bulk";
  }
  return "?";
}

ExchangeMode resolveExchangeMode(ExchangeMode mode, ForwardingMode forwarding) {
  if (mode == ExchangeMode::Auto)
    return forwarding == ForwardingMode::Broadcast ? ExchangeMode::Bulk : ExchangeMode::Overlapped;
  if (mode == ExchangeMode::Overlapped && forwarding == ForwardingMode::Broadcast)
    throw InputError(
        "the overlapped exchange does not do broadcast forwarding (its replies are built on "
        "rounds): use the bulk exchange, or auto");
  return mode;
}

template <typename Path>
DistributedTraversal<Path>::DistributedTraversal(const Communicator& comm,
                                                 const TraceBackend& geometry,
                                                 const Partition& partition,
                                                 const ProxyBvh& proxies, ForwardingMode mode,
                                                 ExchangeMode exchange, uint32_t chunkPixels)
    : comm_(comm),
      geometry_(geometry),
      mode_(mode),
      exchange_(resolveExchangeMode(exchange, mode)),
      chunkPixels_(std::max(1u, chunkPixels)),
      proxies_(proxies) {
  FERRY_CHECK_LE(comm.size(), kMaxRanks);
  if constexpr (!Path::kReplay) {
    FERRY_CHECK_LE(comm.size(), sizeof(typename Path::Mask) * 8);
    instanceOwners_.reserve(partition.instanceOwners.size());
    for (const RankSet& owners : partition.instanceOwners) {
      FERRY_CHECK(owners.fitsInMask());
      instanceOwners_.push_back(owners.mask());
    }
  }
}

template <typename Path>
int DistributedTraversal<Path>::primaryOwner(uint32_t pixel, const TraceRay& ray,
                                             uint32_t& queries) const {
  const uint32_t ranks = uint32_t(comm_.size());
  // Proxy-guided: the owner of the closest proxy keeps it; rays that hit no
  // proxy are dealt by pixel id.
  const ProxyBvh::Hit hit = proxies_.closest(ray.origin, ray.direction, ray.tmax, 0);
  queries = 1;
  if (!hit.found()) return int(pixel % ranks);
  // A replicated proxy: the owner that reaches farthest (forwarding.h,
  // reachingOwners), pixel id among equals.
  const RankSet owners =
      reachingOwners(proxies_, hit, ray.origin, ray.direction, RankSet{}, queries);
  return owners.nth(int(pixel % uint32_t(owners.count())));
}

template <typename Path>
void DistributedTraversal<Path>::primaryPixels(const PixelSet& set, const CameraRays& cameraRays,
                                               std::vector<uint32_t>& pixels, FrameStats& stats) {
  // Each pixel is decided by the rank it is dealt to (pixel % ranks) and sent
  // to its owner as a 4-byte pixel id.
  const uint32_t ranks = uint32_t(comm_.size()), rank = uint32_t(comm_.rank());
  std::vector<uint32_t> dealt;
  set.forEachRun([&](uint32_t first, uint32_t last) {
    const uint32_t firstDealt = first + (rank + ranks - first % ranks) % ranks;
    for (uint32_t pixel = firstDealt; pixel < last; pixel += ranks) dealt.push_back(pixel);
  });
  if (mode_ != ForwardingMode::Proxies) {
    // Ring and broadcast have no proxies to guide them: every rank keeps its deal.
    pixels = std::move(dealt);
    return;
  }
  auto sampleOwners = [&](const std::vector<uint32_t>& of) {
    return owners(of, stats, [&](uint32_t pixel, uint32_t& queries, uint32_t& closest) {
      closest = 1;
      return primaryOwner(pixel, cameraRays.sample(pixel), queries);
    });
  };
  // A pinhole: a pixel whose corners and centre have one owner keeps it for
  // every sample of this view from its second on; the others, a lens's
  // pixels and a view's first sample (a camera that moves every frame pays
  // nothing more) are decided sample by sample. Kept per pixel set (the
  // viewer renders a frame in slices, groups take bands of it), for one view
  // at a time; every rank keeps and drops the same ones.
  sampleView_ = nullptr;
  ViewOwnership* view = nullptr;
  if (cameraRays.through) {
    if (!viewOwnership_.empty() && (viewOwnership_.front().view != cameraRays.view ||
                                    viewOwnership_.size() >= kMaxOwnershipRanges))
      viewOwnership_.clear();
    auto known = std::find_if(viewOwnership_.begin(), viewOwnership_.end(),
                              [&](const auto& v) { return v.set == set; });
    if (known == viewOwnership_.end())
      known = viewOwnership_.insert(known, ViewOwnership{cameraRays.view, set});
    view = &*known;
  }
  if (view == nullptr || !view->seen) {
    if (view) view->seen = true;
    pixels = sendToOwners(dealt, sampleOwners(dealt), stats);
    return;
  }
  if (!view->decided) {
    view->decided = true;
    constexpr float kCorner[5][2] = {{0.5f, 0.5f}, {0, 0}, {1, 0}, {0, 1}, {1, 1}};
    auto ownerOfCorners = [&](uint32_t pixel, uint32_t& queries, uint32_t& closest) {
      int32_t found = -1;
      bool varies = false;
      for (const auto& [dx, dy] : kCorner) {  // all five, so the counts are exact
        uint32_t q = 0;
        const int o = primaryOwner(pixel, cameraRays.through(pixel, dx, dy), q);
        queries += q;
        ++closest;
        varies |= found >= 0 && o != found;
        found = o;
      }
      return varies ? kVariesBySample : found;
    };
    const std::vector<int32_t> owner = owners(dealt, stats, ownerOfCorners);
    std::vector<uint32_t> fixed;
    std::vector<int32_t> fixedOwner;
    for (size_t k = 0; k < dealt.size(); ++k) {
      if (owner[k] == kVariesBySample) {
        view->varying.push_back(dealt[k]);
      } else {
        fixed.push_back(dealt[k]);
        fixedOwner.push_back(owner[k]);
      }
    }
    view->fixed = sendToOwners(fixed, fixedOwner, stats);
    computeClearance(*view, cameraRays);
  }
  sampleView_ = view;
  const std::vector<uint32_t> varying =
      sendToOwners(view->varying, sampleOwners(view->varying), stats);
  pixels.resize(view->fixed.size() + varying.size());
  std::merge(view->fixed.begin(), view->fixed.end(), varying.begin(), varying.end(),
             pixels.begin());
}

template <typename Path>
void DistributedTraversal<Path>::computeClearance(ViewOwnership& view,
                                                  const CameraRays& cameraRays) const {
  view.clearance.assign(view.set.last - view.set.first, 0.0f);
  if constexpr (Path::kReplay) return;  // (decisions there take the visited set, not the mask)
  if (comm_.rank() >= int(8 * sizeof(RankMask))) return;  // (mask layouts have no such rank)
  const RankMask self = RankMask(1) << comm_.rank();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, view.fixed.size(), 256), [&](const auto& range) {
    for (size_t k = range.begin(); k != range.end(); ++k) {
      const uint32_t pixel = view.fixed[k];
      const TraceRay r00 = cameraRays.through(pixel, 0, 0);
      const std::array<Vec3f, 4> corners{r00.direction, cameraRays.through(pixel, 1, 0).direction,
                                         cameraRays.through(pixel, 1, 1).direction,
                                         cameraRays.through(pixel, 0, 1).direction};
      const float c = proxies_.coneClearance(r00.origin, corners, self);
      // Less a margin for the rounding of the query's entry distances, which
      // are computed from coordinates as large as the eye's.
      const Vec3f e = r00.origin;
      const float scale = std::max({std::abs(e.x), std::abs(e.y), std::abs(e.z), 1.0f});
      view.clearance[pixel - view.set.first] =
          std::isinf(c) ? c : std::max(0.0f, c * (1 - 1e-4f) - 1e-4f * scale);
    }
  });
}

template <typename Path>
template <typename OwnerOf>
std::vector<int32_t> DistributedTraversal<Path>::owners(const std::vector<uint32_t>& pixels,
                                                        FrameStats& stats,
                                                        const OwnerOf& ownerOf) const {
  std::vector<int32_t> owner(pixels.size());
  std::atomic<uint64_t> queries{0}, closest{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels.size(), 1024), [&](const auto& range) {
    uint64_t localQueries = 0, localClosest = 0;
    for (size_t k = range.begin(); k != range.end(); ++k) {
      uint32_t q = 0, c = 0;
      owner[k] = ownerOf(pixels[k], q, c);
      localQueries += q;
      localClosest += c;
    }
    queries += localQueries;
    closest += localClosest;
  });
  stats.proxyQueries += queries;
  stats.primaryQueries += closest;
  stats.replicaQueries += queries - closest;
  return owner;
}

template <typename Path>
std::vector<uint32_t> DistributedTraversal<Path>::sendToOwners(const std::vector<uint32_t>& pixels,
                                                               const std::vector<int32_t>& owner,
                                                               FrameStats& stats) const {
  const uint32_t ranks = uint32_t(comm_.size());
  // Pixel ids by owner, each owner's in increasing order.
  std::vector<int> counts(ranks, 0), offsets(ranks, 0);
  for (int32_t o : owner) ++counts[size_t(o)];
  for (uint32_t r = 1; r < ranks; ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
  std::vector<uint32_t> send(pixels.size());
  std::vector<int> cursor = offsets;
  for (size_t k = 0; k < pixels.size(); ++k) send[size_t(cursor[size_t(owner[k])]++)] = pixels[k];
  // The counts' collective is where a rank waits for the slowest (stage
  // "wait"); moving the ids is the exchange proper (stage "exchange").
  auto start = Clock::now();
  std::vector<int> receiveCounts = comm_.exchangeCounts(counts);
  stats.times.wait += secondsSince(start);
  start = Clock::now();
  std::vector<int> receiveOffsets(ranks, 0);
  for (uint32_t r = 1; r < ranks; ++r)
    receiveOffsets[r] = receiveOffsets[r - 1] + receiveCounts[r - 1];
  std::vector<uint32_t> received(size_t(receiveOffsets[ranks - 1]) +
                                 size_t(receiveCounts[ranks - 1]));
  auto toBytes = [](std::vector<int> v) {
    for (int& x : v) x *= int(sizeof(uint32_t));
    return v;
  };
  comm_.exchangeBytes(send.data(), toBytes(counts), toBytes(offsets), received.data(),
                      toBytes(receiveCounts), toBytes(receiveOffsets));
  stats.times.exchange += secondsSince(start);
  stats.primaryBytesSent +=
      (pixels.size() - size_t(counts[size_t(comm_.rank())])) * sizeof(uint32_t);
  // Each source's ids are increasing; the queue wants them all in pixel order.
  std::sort(received.begin(), received.end());
  return received;
}

template <typename Path>
void DistributedTraversal<Path>::trace(PathQueue<Path>& rays, FrameStats& stats,
                                       std::vector<TraceHit>* hits) {
  const int rank = comm_.rank();
  for (const Path& p : rays) {
    if constexpr (Path::kReplay) {
      if (p.generatingRank == rank) ++revisits_;
    } else {
      if ((uint64_t(p.visited) >> rank) & 1) ++revisits_;
    }
  }
  if (hits) hits->resize(rays.size());
  traceCounted(geometry_, rays, rank, instanceOwners_,
               hits ? std::span<TraceHit>(*hits) : std::span<TraceHit>(), this->times_, stats);
}

template <typename Path>
void DistributedTraversal<Path>::traceArrivals(PathQueue<Path>& rays, std::vector<TraceHit>& hits,
                                               ExchangeCounters& counters, FrameStats& stats) {
  trace(rays, stats, &hits);
  // A shadow ray arrives unoccluded (an occluded one is dropped where it is
  // found), a path with the closest hit found so far: found nothing here
  // means still unoccluded, or no closer hit here.
  uint64_t without = 0;
  for (size_t i = 0; i < rays.size(); ++i)
    without += rays[i].isShadow() ? !rays[i].has(kPathOccluded) : !hits[i].valid();
  counters.visitsWithoutHit += without;
}

template <typename Path>
std::vector<RankSet> DistributedTraversal<Path>::replayArrivals(const PathQueue<Path>& rays,
                                                                FrameStats& stats) {
  auto start = Clock::now();
  const int rank = comm_.rank();
  std::vector<RankSet> visited(rays.size());
  std::atomic<uint64_t> failed{0}, queries{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 256), [&](const auto& range) {
    uint64_t localFailed = 0, localQueries = 0;
    for (size_t i = range.begin(); i != range.end(); ++i) {
      if constexpr (Path::kReplay) {
        ReplayResult r = replayWalk(proxies_, rays[i], rays[i].generatingRank, rank);
        localQueries += r.queries;
        if (!r.reached) {
          ++localFailed;
          r.visited.insert(rank);
        }
        visited[i] = std::move(r.visited);
      }
    }
    failed += localFailed;
    queries += localQueries;
  });
  revisits_ += failed;
  stats.replayQueries += queries;
  stats.times.exchange += secondsSince(start);
  return visited;
}

template <typename Path>
PathQueue<Path> DistributedTraversal<Path>::exchange(const PathQueue<Path>& rays,
                                                     const std::vector<int>& destination,
                                                     ExchangeCounters& counters,
                                                     FrameStats& stats) {
  auto start = Clock::now();
  if (firstExchange_) {
    maybeInjectFailure("exchange", comm_.rank());
    firstExchange_ = false;
  }
  const int ranks = comm_.size();
  std::vector<int> counts(ranks, 0);
  for (int d : destination) ++counts[d];
  // Compact by destination, keeping each destination's rays in queue order.
  std::vector<int> offsets(ranks, 0);
  for (int r = 1; r < ranks; ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
  PathQueue<Path> send(rays.size());
  std::vector<int> cursor = offsets;
  for (size_t i = 0; i < rays.size(); ++i) send[cursor[destination[i]]++] = rays[i];

  std::vector<int> receiveCounts = comm_.exchangeCounts(counts);
  std::vector<int> receiveOffsets(ranks, 0);
  for (int r = 1; r < ranks; ++r) receiveOffsets[r] = receiveOffsets[r - 1] + receiveCounts[r - 1];
  size_t total = size_t(receiveOffsets[ranks - 1]) + size_t(receiveCounts[ranks - 1]);
  PathQueue<Path> received(total);

  auto toBytes = [](std::vector<int> v) {
    for (int& x : v) {
      if (int64_t(x) * int64_t(sizeof(Path)) > INT32_MAX)
        throw std::runtime_error("ray exchange exceeds 2 GiB in one message");
      x *= int(sizeof(Path));
    }
    return v;
  };
  comm_.exchangeBytes(send.data(), toBytes(counts), toBytes(offsets), received.data(),
                      toBytes(receiveCounts), toBytes(receiveOffsets));
  counters.countSent(send.data(), send.size(), sizeof(Path));
  if (comm_.isRoot()) ++counters.rounds;  // a round is one collective step; counted once
  received_ += total;
  stats.times.exchange += secondsSince(start);
  return received;
}

template <typename Path>
void DistributedTraversal<Path>::traverse(RayQueues<Path>& rays, std::vector<TraceHit>& pathHits,
                                          ExchangeCounters& exchange, FrameStats& stats) {
  // Paths and shadow rays travel as one queue (the path format is the same;
  // kPathShadow tells them apart): one exchange per round for both.
  PathQueue<Path> wavefront = std::move(rays.paths);
  wavefront.insert(wavefront.end(), rays.shadowRays.begin(), rays.shadowRays.end());
  rays.clear();
  pathHits.clear();
  if (mode_ == ForwardingMode::Broadcast)
    traverseBroadcast(std::move(wavefront), rays, pathHits, exchange, stats);
  else
    traverseForwarding(std::move(wavefront), rays, pathHits, exchange, stats);
}

template <typename Path>
void DistributedTraversal<Path>::traverseForwarding(PathQueue<Path> moving, RayQueues<Path>& ready,
                                                    std::vector<TraceHit>& readyHits,
                                                    ExchangeCounters& counters, FrameStats& stats) {
  const int rank = comm_.rank();
  // `ready` gets the rays whose traversal is complete here (shade on this
  // rank), each path with its hit when its last trace, here, found it (shading
  // then need not re-trace it); invalid for rays that arrive to be shaded.
  std::vector<TraceHit> movingHits;
  // Replay layout (proxies): the visited set of each ray in `moving`, this rank
  // included; new rays have visited only this rank.
  const bool replay = Path::kReplay && mode_ == ForwardingMode::Proxies;
  std::vector<RankSet> visited;
  if (replay) visited.assign(moving.size(), RankSet::single(rank));
  // Local first: every new ray is traced on the rank that made it.
  trace(moving, stats, &movingHits);
  std::vector<int> destination;
  for (;;) {
    auto start = Clock::now();
    decide(moving, visited, destination, stats);
    // Split: kept, dropped, and leaving.
    PathQueue<Path> leaving;
    std::vector<int> leavingTo;
    for (size_t i = 0; i < moving.size(); ++i) {
      if (destination[i] == kShadeHere) {
        keepToShade(moving[i], movingHits[i], ready, readyHits);
      } else if (destination[i] >= 0) {
        leaving.push_back(moving[i]);
        leavingTo.push_back(destination[i]);
      }
    }
    stats.times.exchange += secondsSince(start);
    if (comm_.sum(uint64_t(leaving.size())) == 0) break;
    PathQueue<Path> received = exchange(leaving, leavingTo, counters, stats);
    moving.clear();
    for (Path& p : received) {
      if (p.has(kPathTraversed)) {
        keepToShade(p, TraceHit{}, ready, readyHits);
      } else {
        moving.push_back(p);
      }
    }
    // Replay before tracing: the walk is replayed with the tmax the ray arrived with.
    if (replay) visited = replayArrivals(moving, stats);
    traceArrivals(moving, movingHits, counters, stats);
  }
}

template <typename Path>
void DistributedTraversal<Path>::decide(PathQueue<Path>& rays, const std::vector<RankSet>& visited,
                                        std::vector<int>& destination, FrameStats& stats,
                                        const ViewOwnership* cameraClearance) const {
  const int rank = comm_.rank();
  const int ranks = comm_.size();
  destination.resize(rays.size());
  std::atomic<uint64_t> proxyQueries{0}, replicaQueries{0}, skippedQueries{0};
  if (mode_ != ForwardingMode::Proxies || Path::kReplay) cameraClearance = nullptr;
  // A camera ray (not a light path's first ray) that hit here nearer than its
  // pixel's clearance: no other rank's proxy is entered before its hit.
  auto clear = [&](const Path& ray) {
    if (!cameraClearance || ray.isShadow() || ray.has(kPathLight)) return false;
    const uint32_t pixel = ray.pixel();
    const ViewOwnership& v = *cameraClearance;
    return pixel >= v.set.first && pixel < v.set.last &&
           ray.tmax <= v.clearance[pixel - v.set.first];
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024), [&](const auto& range) {
    uint64_t queries = 0, replica = 0, skipped = 0;
    for (size_t i = range.begin(); i != range.end(); ++i) {
      ForwardDecision d;
      if (clear(rays[i])) {
        d = finishTraversal(rays[i], rank);
        ++skipped;
      } else if (mode_ == ForwardingMode::Ring)
        d = forwardByRing(rays[i], rank, ranks);
      else if constexpr (Path::kReplay)
        d = forwardByProxies(proxies_, rays[i], rank, visited[i]);
      else
        d = forwardByProxies(proxies_, rays[i], rank);
      destination[i] = decisionToDestination(d, rays[i], rank);
      queries += d.queries;
      replica += d.queries > 1 ? d.queries - 1 : 0;  // the first: the closest proxy
    }
    proxyQueries += queries;
    replicaQueries += replica;
    skippedQueries += skipped;
  });
  stats.proxyQueries += proxyQueries;
  stats.replicaQueries += replicaQueries;
  stats.skippedQueries += skippedQueries;
}

template <typename Path>
void DistributedTraversal<Path>::traverseBroadcast(PathQueue<Path> rays, RayQueues<Path>& ready,
                                                   std::vector<TraceHit>& readyHits,
                                                   ExchangeCounters& counters, FrameStats& stats) {
  const int rank = comm_.rank();
  const int ranks = comm_.size();
  std::vector<TraceHit> ownHits;
  trace(rays, stats, &ownHits);  // the origin's own answer

  // 1. A copy of every undecided ray to every other rank.
  PathQueue<Path> copies;
  std::vector<int> copiesTo;
  for (const Path& p : rays) {
    if (p.isShadow() && p.has(kPathOccluded)) continue;
    for (int r = 0; r < ranks; ++r)
      if (r != rank) {
        copies.push_back(p);
        copiesTo.push_back(r);
      }
  }
  PathQueue<Path> received = exchange(copies, copiesTo, counters, stats);
  std::vector<TraceHit> copyHits;
  traceArrivals(received, copyHits, counters, stats);

  // 2. Every copy goes back to its origin (the one visited rank besides this one).
  std::vector<int> replyTo(received.size());
  for (size_t i = 0; i < received.size(); ++i) {
    received[i].set(kPathReply);
    if constexpr (Path::kReplay)
      replyTo[i] = received[i].generatingRank;
    else
      replyTo[i] = std::countr_zero(RankMask(received[i].visited) & ~(RankMask(1) << rank));
  }
  PathQueue<Path> replies = exchange(received, replyTo, counters, stats);

  // The closest hit wins; any occluder occludes. A rank makes at most one path
  // and one shadow ray per pixel per wavefront, and as many of a light path
  // (whose pixel() is its index), so (pixel, kind, light) finds the original.
  auto start = Clock::now();
  std::unordered_map<uint64_t, size_t> original;
  original.reserve(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) original[replyKey(rays[i])] = i;
  for (const Path& reply : replies) {
    auto it = original.find(replyKey(reply));
    FERRY_CHECK(it != original.end());
    Path& p = rays[it->second];
    if constexpr (!Path::kReplay) p.visited |= reply.visited;
    if (p.isShadow()) {
      if (reply.has(kPathOccluded)) p.set(kPathOccluded);
    } else if (reply.hasHit() && reply.tmax < p.tmax) {
      p.tmax = reply.tmax;
      if constexpr (Path::kReplay)
        p.hitRank = reply.hitRank;
      else
        p.hitOwners = reply.hitOwners;
      ownHits[it->second] = TraceHit{};  // another rank's hit is closer
    }
  }

  // 3. Shade where the hit is.
  PathQueue<Path> leaving;
  std::vector<int> leavingTo;
  for (size_t i = 0; i < rays.size(); ++i) {
    Path& p = rays[i];
    int d = decisionToDestination(finishTraversal(p, rank), p, rank);
    if (d == kShadeHere) {
      keepToShade(p, ownHits[i], ready, readyHits);
    } else if (d >= 0) {
      leaving.push_back(p);
      leavingTo.push_back(d);
    }
  }
  stats.times.exchange += secondsSince(start);
  for (const Path& p : exchange(leaving, leavingTo, counters, stats))
    keepToShade(p, TraceHit{}, ready, readyHits);
}

template class DistributedTraversal<Path8>;
template class DistributedTraversal<Path64>;
template class DistributedTraversal<PathReplay>;
template class DistributedTraversal<PathProbe>;

}  // namespace ferry
