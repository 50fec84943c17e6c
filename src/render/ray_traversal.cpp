#include "render/ray_traversal.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <span>

#include "core/clock.h"
#include "render/path.h"

namespace ferry {

template <typename Path>
void traceLocally(const LocalGeometry& geometry, std::vector<Path>& rays, int rank,
                  std::span<const uint64_t> instanceOwners, FrameStats& stats, TraceHit* found) {
  auto start = Clock::now();
  // Batches of closest-hit and shadow queries in queue order, built, traced and
  // applied on the worker thread that owns them (no whole-wavefront arrays, no
  // serial pass).
  constexpr size_t kBatch = 256;
  std::atomic<uint64_t> closestCount{0}, shadowCount{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kBatch), [&](const tbb::blocked_range<size_t>& range) {
    TraceRay batch[kBatch];
    TraceQuery queries[kBatch];
    TraceHit hits[kBatch];
    uint8_t occluded[kBatch];
    uint64_t closest = 0, shadow = 0;
    for (size_t begin = range.begin(); begin < range.end(); begin += kBatch) {
      const size_t n = std::min(kBatch, range.end() - begin);
      for (size_t i = 0; i < n; ++i) {
        const Path& p = rays[begin + i];
        if (p.isShadow() && p.has(kPathOccluded)) {  // already decided elsewhere
          queries[i] = TraceQuery::None;
          continue;
        }
        batch[i] = TraceRay{p.origin, p.dir(), 0.0f, p.tmax};
        queries[i] = p.isShadow() ? TraceQuery::Occluded : TraceQuery::Closest;
        ++(p.isShadow() ? shadow : closest);
      }
      geometry.traceBatch(std::span(batch, n), std::span(queries, n), std::span(hits, n), std::span(occluded, n));
      for (size_t i = 0; i < n; ++i) {
        Path& p = rays[begin + i];
        bool setHere = false;
        if (queries[i] == TraceQuery::Closest) {
          if (hits[i].valid() && hits[i].t < p.tmax) {
            p.tmax = hits[i].t;
            p.setHit(rank, instanceOwners.empty() ? 0 : instanceOwners[hits[i].instance]);
            setHere = true;
          }
        } else if (queries[i] == TraceQuery::Occluded && occluded[i]) {
          p.set(kPathOccluded);
        }
        p.markTraced(rank);
        if (found) found[begin + i] = setHere ? hits[i] : TraceHit{};
      }
    }
    closestCount += closest;
    shadowCount += shadow;
  });
  stats.closestTraces += closestCount;
  stats.occlusionTraces += shadowCount;
  stats.times.trace += secondsSince(start);
}

template void traceLocally<Path8>(const LocalGeometry&, std::vector<Path8>&, int, std::span<const uint64_t>,
                                  FrameStats&, TraceHit*);
template void traceLocally<Path64>(const LocalGeometry&, std::vector<Path64>&, int, std::span<const uint64_t>,
                                   FrameStats&, TraceHit*);
template void traceLocally<PathReplay>(const LocalGeometry&, std::vector<PathReplay>&, int,
                                       std::span<const uint64_t>, FrameStats&, TraceHit*);

}  // namespace ferry
