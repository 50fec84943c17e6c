// The forwarding operator: given a ray that has just been traced on `rank`,
// where does it go next? Pure functions of the ray, the proxies and the rank,
// so any rank decides the same way (paper, Section 3.3).
#pragma once

#include <cstdint>
#include <string>

#include "distributed/proxy_bvh.h"
#include "partition/partition.h"
#include "path/path.h"

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
  uint32_t queries = 0;  // proxy-BVH queries the decision took
};

// One owner among `owners`, picked pseudo-randomly but deterministically from
// the ray (its pixel, flags and origin: the same on every rank and in every
// layout). The two forms pick the same rank for the same set.
int pickOwner(RankMask owners, const PathCore& ray);
int pickOwner(const RankSet& owners, const PathCore& ray);

// Which owners of a proxy the ray is to visit next (`hit`: the closest proxy
// none of whose owners is in `visited`) may take it: the owners whose own
// proxies carry it farthest, i.e. whose first proxy it enters that neither
// they nor a visited rank hold comes last (tmax ignored, so the answer does
// not change as hits shorten the ray: the replay layout recomputes it). An
// unreplicated proxy's one owner; for a replica (a copy of large, cheap
// content on several ranks) the one that holds the most of what the ray
// passes next (docs/data-parallel.md, "Replicas"). Adds the queries it makes
// to `queries`.
RankSet reachingOwners(const ProxyBvh& proxies, const ProxyBvh::Hit& hit, Vec3f origin,
                       Vec3f direction, const RankSet& visited, uint32_t& queries);

// Traversal done on `rank`: shade here if it holds the hit (or there is none),
// else send to one of the hit's owners (replay layout: to the rank that found
// it); occluded shadow rays are dropped.
template <typename Path>
ForwardDecision finishTraversal(const Path& ray, int rank);

// Mask layouts: the visited set is the ray's own mask.
template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank);
// Any layout: `visited` holds every rank the ray has been traced on, `rank` included.
template <typename Path>
ForwardDecision forwardByProxies(const ProxyBvh& proxies, const Path& ray, int rank,
                                 const RankSet& visited);

// Mask layouts: the first unvisited rank after `rank` in ring order. Replay
// layout: the ring from the generating rank has visited exactly the ranks from
// there to `rank`, so the next is rank + 1 unless that is where it started.
template <typename Path>
ForwardDecision forwardByRing(const Path& ray, int rank, int ranks);

// The paper's "replay" (Section 3.3): the set of ranks a ray has visited,
// recomputed from only the rank that generated it, by re-running the proxy
// decisions from there until the walk reaches `current`. With `ray.tmax` as
// it arrived at `current` (before `current` traces it) the walk visits
// exactly the ranks a carried mask would hold, with no more state on the ray
// (docs/data-parallel.md, "Above 64 ranks: replay", says why).
//
// `reached` is false if the walk ends without reaching `current`: the ray's
// history is not what the replay says (counted as a revisit).
struct ReplayResult {
  RankSet visited;  // ranks the ray has been traced on before `current`, plus `current` if reached
  bool reached = false;
  uint32_t queries = 0;  // proxy queries spent
};
template <typename Path>
ReplayResult replayWalk(const ProxyBvh& proxies, const Path& ray, int generatingRank, int current);

}  // namespace ferry
