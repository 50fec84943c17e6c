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
  throw InputError(fmt::format("--forwarding '{}': expected proxies, ring or broadcast", name));
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

namespace {
// The owner of the proxy a query found: its owners come with the answer.
int pickOwner(const ProxyBvh::Hit& hit, const PathCore& ray) {
  return hit.ownerSet ? pickOwner(*hit.ownerSet, ray) : pickOwner(hit.ownerMask, ray);
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
    if (owners == 0 || (owners & (RankMask(1) << rank))) return {ForwardDecision::ShadeHere};
    return {ForwardDecision::Send, pickOwner(owners, ray), true};
  }
}

template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank) {
  if (ray.isShadow() && ray.has(kPathOccluded))
    return {ForwardDecision::Drop};  // ends at any occluder
  ProxyBvh::Hit next = proxies.closest(ray.origin, ray.dir(), ray.tmax, RankMask(ray.visited));
  if (next.found()) return {ForwardDecision::Send, pickOwner(next, ray)};
  return finishTraversal(ray, rank);
}

template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank,
                                 const RankSet& visited) {
  if (ray.isShadow() && ray.has(kPathOccluded)) return {ForwardDecision::Drop};
  ProxyBvh::Hit next = proxies.closest(ray.origin, ray.dir(), ray.tmax, visited);
  if (next.found()) return {ForwardDecision::Send, pickOwner(next, ray)};
  return finishTraversal(ray, rank);
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
    ++result.queries;
    ProxyBvh::Hit next = proxies.closest(ray.origin, dir, ray.tmax, result.visited);
    if (!next.found()) return result;
    at = pickOwner(next, ray);
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
template ForwardDecision forwardByProxies<Path8>(const ProxyBvh&, const Path8&, int);
template ForwardDecision forwardByProxies<Path64>(const ProxyBvh&, const Path64&, int);
#undef FERRY_INSTANTIATE

}  // namespace ferry
