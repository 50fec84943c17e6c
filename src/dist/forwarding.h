// The forwarding operator: given a ray that has just been traced on `rank`,
// where does it go next? Pure functions of the ray, the proxies and the rank,
// so any rank decides the same way (paper, Section 3.3).
#pragma once

#include <cstdint>
#include <string>

#include "partition/partition.h"
#include "render/path.h"
#include "trace/proxy_bvh.h"

namespace ferry {

enum class ForwardingMode {
  Proxies,    // the paper: closest proxy of an unvisited owner
  Ring,       // every ray visits every rank in turn (barney)
  Broadcast,  // every ray goes to every rank, the closest hit wins (Kilauea)
};
ForwardingMode parseForwardingMode(const std::string& name);  // throws InputError
std::string toString(ForwardingMode mode);

struct ForwardDecision {
  enum Kind : uint8_t { ShadeHere, Drop, Send } kind = ShadeHere;
  int rank = -1;         // for Send
  bool toShade = false;  // Send: traversal is complete, the receiver only shades
};

// One owner among `owners`, picked pseudo-randomly but deterministically from the ray.
template <typename Path>
int pickOwner(RankMask owners, const Path& ray);

// Traversal done on `rank`: shade here if it holds the hit (or there is none),
// else send to one of the hit's owners; occluded shadow rays are dropped.
template <typename Path>
ForwardDecision finishTraversal(const Path& ray, int rank);

template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank);

template <typename Path>
ForwardDecision forwardByRing(const Path& ray, int rank, int ranks);

// The paper's "replay": the set of ranks a ray has visited, recomputed from
// only the rank that generated it, by re-running the proxy decisions (used
// above 64 ranks, where a mask per ray no longer fits). Returns the visited
// set as it would be on arrival at `current`; stops when it reaches `current`.
template <typename Path>
RankMask replayVisited(const ProxyBvh& proxies, const Path& ray, int generatingRank, int current);

}  // namespace ferry
