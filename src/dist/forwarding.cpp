#include "dist/forwarding.h"

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

template <typename Path>
int pickOwner(RankMask owners, const Path& ray) {
  int count = std::popcount(owners);
  FERRY_CHECK(count > 0);
  uint32_t bits;
  std::memcpy(&bits, &ray.origin.x, 4);
  uint32_t h = hashCombine(hashMix(ray.pixelAndFlags & ~uint32_t(kPathTraversed | kPathReply)), bits);
  int k = int(h % uint32_t(count));
  for (;; --k) {
    int r = std::countr_zero(owners);
    if (k == 0) return r;
    owners &= owners - 1;
  }
}

template <typename Path>
ForwardDecision finishTraversal(const Path& ray, int rank) {
  if (ray.isShadow()) return {ray.has(kPathOccluded) ? ForwardDecision::Drop : ForwardDecision::ShadeHere};
  RankMask owners = RankMask(ray.hitOwners);
  if (owners == 0 || (owners & (RankMask(1) << rank))) return {ForwardDecision::ShadeHere};
  return {ForwardDecision::Send, pickOwner(owners, ray), true};
}

template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank) {
  if (ray.isShadow() && ray.has(kPathOccluded)) return {ForwardDecision::Drop};  // ends at any occluder
  ProxyBvh::Hit next = proxies.closest(ray.origin, ray.dir(), ray.tmax, RankMask(ray.visited));
  if (next.found()) return {ForwardDecision::Send, pickOwner(proxies.proxies()[next.proxy].owners.mask(), ray)};
  return finishTraversal(ray, rank);
}

template <typename Path>
ForwardDecision forwardByRing(const Path& ray, int rank, int ranks) {
  if (ray.isShadow() && ray.has(kPathOccluded)) return {ForwardDecision::Drop};
  for (int step = 1; step < ranks; ++step) {
    int next = (rank + step) % ranks;
    if (!(RankMask(ray.visited) & (RankMask(1) << next))) return {ForwardDecision::Send, next};
  }
  return finishTraversal(ray, rank);
}

template <typename Path>
RankMask replayVisited(const ProxyBvh& proxies, const Path& ray, int generatingRank, int current) {
  RankMask visited = RankMask(1) << generatingRank;
  int at = generatingRank;
  while (at != current) {
    ProxyBvh::Hit next = proxies.closest(ray.origin, ray.dir(), ray.tmax, visited);
    if (!next.found()) break;
    Path probe = ray;
    at = pickOwner(proxies.proxies()[next.proxy].owners.mask(), probe);
    visited |= RankMask(1) << at;
  }
  return visited;
}

#define FERRY_INSTANTIATE(P)                                                            \
  template int pickOwner<P>(RankMask, const P&);                                        \
  template ForwardDecision finishTraversal<P>(const P&, int);                           \
  template ForwardDecision forwardByProxies<P>(const ProxyBvh&, const P&, int);         \
  template ForwardDecision forwardByRing<P>(const P&, int, int);                        \
  template RankMask replayVisited<P>(const ProxyBvh&, const P&, int, int);
FERRY_INSTANTIATE(Path8)
FERRY_INSTANTIATE(Path64)
#undef FERRY_INSTANTIATE

}  // namespace ferry
