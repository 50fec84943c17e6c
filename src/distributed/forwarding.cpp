#include "distributed/forwarding.h"

#include <bit>
#include <cstring>

#include <fmt/format.h>

#include "core/error.h"
#include "core/random.h"

namespace ferry {

ForwardingMode parseForwardingMode(const std::string& name) {
  if (name == "proxies") return ForwardingMode::Proxies;
  if (name == "ring") return ForwardingMode::Ring;
  if (name == "broadcast") return ForwardingMode::Broadcast;
  throw InputError(fmt::format("forwarding '{}': expected proxies, ring or broadcast", name));
}

std::string toString(ForwardingMode mode) {
  switch (mode) {
    case ForwardingMode::Proxies:
      return "proxies";
    case ForwardingMode::Ring:
      return "ring";
    case ForwardingMode::Broadcast:
      return "broadcast";
  }
  return "?";
}

namespace {
uint32_t ownerHash(const PathCore& ray) {
  uint32_t bits;
  std::memcpy(&bits, &ray.origin.x, 4);
  return hashCombine(hashMix(ray.pixelAndFlags & ~uint32_t(kPathTraversed | kPathReply)), bits);
}
}  // namespace

int pickOwner(RankMask owners, const PathCore& ray) {
  int count = std::popcount(owners);
  FERRY_CHECK_GT(count, 0);
  int k = int(ownerHash(ray) % uint32_t(count));
  for (;; --k) {
    int r = std::countr_zero(owners);
    if (k == 0) return r;
    owners &= owners - 1;
  }
}

int pickOwner(const RankSet& owners, const PathCore& ray) {
  if (owners.fitsInMask()) return pickOwner(owners.mask(), ray);
  int count = owners.count();
  return owners.nth(int(ownerHash(ray) % uint32_t(count)));
}

RankSet reachingOwners(const ProxyBvh& proxies, const ProxyBvh::Hit& hit, Vec3f origin,
                       Vec3f direction, const RankSet& visited, uint32_t& queries) {
  RankSet owners = hit.owners();
  if (owners.count() <= 1) return owners;
  const bool narrow = proxies.narrow() && visited.fitsInMask();
  float farthest = -1;
  RankSet reachers;
  for (int k = 0; k < owners.count(); ++k) {
    const int owner = owners.nth(k);
    ProxyBvh::Hit other;
    if (narrow) {
      other =
          proxies.closest(origin, direction, kInfinity, visited.mask() | (RankMask(1) << owner));
    } else {
      RankSet excluded = visited;
      excluded.insert(owner);
      other = proxies.closest(origin, direction, kInfinity, excluded);
    }
    ++queries;
    const float reach = other.found() ? other.tEnter : kInfinity;
    if (reach > farthest) {
      farthest = reach;
      reachers = RankSet::single(owner);
    } else if (reach == farthest) {
      reachers.insert(owner);
    }
  }
  return reachers;
}

namespace {
// The next rank for a ray whose closest unvisited proxy is `hit`.
ForwardDecision sendTo(const ProxyBvh& proxies, const ProxyBvh::Hit& hit, const PathCore& ray,
                       Vec3f direction, const RankSet& visited) {
  ForwardDecision d{ForwardDecision::Send};
  d.queries = 1;
  if (!hit.ownerSet && std::has_single_bit(hit.ownerMask)) {
    d.rank = std::countr_zero(hit.ownerMask);
    return d;
  }
  d.rank = pickOwner(reachingOwners(proxies, hit, ray.origin, direction, visited, d.queries), ray);
  return d;
}

// The decision after the query for the closest unvisited proxy (`next`).
template <typename Path>
ForwardDecision decideAfterQuery(const ProxyBvh& proxies, const ProxyBvh::Hit& next,
                                 const Path& ray, Vec3f direction, const RankSet& visited,
                                 int rank) {
  if (next.found()) return sendTo(proxies, next, ray, direction, visited);
  ForwardDecision d = finishTraversal(ray, rank);
  d.queries = 1;
  return d;
}
}  // namespace

template <typename Path>
ForwardDecision finishTraversal(const Path& ray, int rank) {
  if (ray.isShadow())
    return {ray.has(kPathOccluded) ? ForwardDecision::Drop : ForwardDecision::ShadeHere};
  if constexpr (Path::kReplay) {
    if (!ray.hasHit() || ray.hitRank == rank) return {ForwardDecision::ShadeHere};
    return {ForwardDecision::Send, int(ray.hitRank), true};
  } else {
    RankMask owners = RankMask(ray.hitOwners);
    // A rank beyond the mask's bits (a mask path checked against a rank set
    // above 64 ranks) owns nothing the mask can name.
    const bool ownsHit = rank < int(8 * sizeof(RankMask)) && (owners & (RankMask(1) << rank));
    if (owners == 0 || ownsHit) return {ForwardDecision::ShadeHere};
    return {ForwardDecision::Send, pickOwner(owners, ray), true};
  }
}

template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank) {
  if (ray.isShadow() && ray.has(kPathOccluded))
    return {ForwardDecision::Drop};  // ends at any occluder
  const Vec3f direction = ray.dir();
  const ProxyBvh::Hit next =
      proxies.closest(ray.origin, direction, ray.tmax, RankMask(ray.visited));
  return decideAfterQuery(proxies, next, ray, direction, RankSet::fromMask(RankMask(ray.visited)),
                          rank);
}

template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank,
                                 const RankSet& visited) {
  if (ray.isShadow() && ray.has(kPathOccluded)) return {ForwardDecision::Drop};
  const Vec3f direction = ray.dir();
  const ProxyBvh::Hit next = proxies.closest(ray.origin, direction, ray.tmax, visited);
  return decideAfterQuery(proxies, next, ray, direction, visited, rank);
}

template <typename Path>
ForwardDecision forwardByRing(const Path& ray, int rank, int ranks) {
  if (ray.isShadow() && ray.has(kPathOccluded)) return {ForwardDecision::Drop};
  if constexpr (Path::kReplay) {
    const int next = (rank + 1) % ranks;
    if (next != int(ray.generatingRank)) return {ForwardDecision::Send, next};
  } else {
    for (int step = 1; step < ranks; ++step) {
      int next = (rank + step) % ranks;
      if (!(RankMask(ray.visited) & (RankMask(1) << next))) return {ForwardDecision::Send, next};
    }
  }
  return finishTraversal(ray, rank);
}

template <typename Path>
ReplayResult replayWalk(const ProxyBvh& proxies, const Path& ray, int generatingRank, int current) {
  ReplayResult result;
  result.visited = RankSet::single(generatingRank);
  const Vec3f dir = ray.dir();
  int at = generatingRank;
  while (at != current) {
    ProxyBvh::Hit next = proxies.closest(ray.origin, dir, ray.tmax, result.visited);
    if (!next.found()) {
      ++result.queries;
      return result;
    }
    const ForwardDecision d = sendTo(proxies, next, ray, dir, result.visited);
    result.queries += d.queries;
    at = d.rank;
    result.visited.insert(at);
  }
  result.reached = true;
  return result;
}

#define FERRY_INSTANTIATE(P)                                                                    \
  template ForwardDecision finishTraversal<P>(const P&, int);                                   \
  template ForwardDecision forwardByProxies<P>(const ProxyBvh&, const P&, int, const RankSet&); \
  template ForwardDecision forwardByRing<P>(const P&, int, int);                                \
  template ReplayResult replayWalk<P>(const ProxyBvh&, const P&, int, int);
FERRY_INSTANTIATE(Path8)
FERRY_INSTANTIATE(Path64)
FERRY_INSTANTIATE(PathReplay)
FERRY_INSTANTIATE(PathProbe)
template ForwardDecision forwardByProxies<Path8>(const ProxyBvh&, const Path8&, int);
template ForwardDecision forwardByProxies<Path64>(const ProxyBvh&, const Path64&, int);
#undef FERRY_INSTANTIATE

}  // namespace ferry
