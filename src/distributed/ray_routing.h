// Where a ray goes once its forwarding decision is made, shared by both
// exchanges of the distributed traversal (bulk rounds and overlapped).
#pragma once

#include <vector>

#include "distributed/forwarding.h"
#include "path/path.h"
#include "trace/trace_backend.h"

namespace ferry {

constexpr int kShadeHere = -1;
constexpr int kDrop = -2;

// A destination rank, or kShadeHere / kDrop; marks rays sent only to be shaded.
template <typename Path>
int decisionToDestination(const ForwardDecision& d, Path& ray, int rank) {
  if (d.kind == ForwardDecision::Drop) return kDrop;
  if (d.kind == ForwardDecision::ShadeHere || d.rank == rank) return kShadeHere;
  if (d.toShade) ray.set(kPathTraversed);
  return d.rank;
}

// A ray whose traversal ended on this rank, into the queue of its kind; a
// path with its kept hit (invalid: shading re-traces it).
template <typename Path>
void keepToShade(const Path& ray, const TraceHit& hit, RayQueues<Path>& ready,
                 std::vector<TraceHit>& readyHits) {
  if (ray.isShadow()) {
    ready.shadowRays.push_back(ray);
  } else {
    ready.paths.push_back(ray);
    readyHits.push_back(hit);
  }
}

}  // namespace ferry
