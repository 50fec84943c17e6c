#include "render/ray_traversal.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <span>

#include "core/clock.h"
#include "trace/path.h"

namespace ferry {

template <typename Path>
void traceLocally(const LocalGeometry& geometry, PathQueue<Path>& rays, int rank,
                  std::span<const uint64_t> instanceOwners, FrameStats& stats, TraceHit* found) {
  auto start = Clock::now();
  // Batches of closest-hit and shadow queries in queue order, built, traced and
  // applied on the worker thread that owns them (no whole-wavefront arrays, no
  // serial pass), each ray written once in Embree's layout (RayBatch).
  constexpr size_t kBatch = RayBatch::kCapacity;
  std::atomic<uint64_t> closestCount{0}, shadowCount{0};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), kBatch),
                    [&](const tbb::blocked_range<size_t>& range) {
                      RayBatch batch;
                      uint64_t closest = 0, shadow = 0;
                      for (size_t begin = range.begin(); begin < range.end(); begin += kBatch) {
                        const size_t n = std::min(kBatch, range.end() - begin);
                        batch.clear();
                        for (size_t i = begin; i < begin + n; ++i) {
                          Path& p = rays[i];
                          p.markTraced(rank);
                          if (found) found[i] = TraceHit{};
                          if (!p.isShadow())
                            batch.addClosest(uint32_t(i), p.origin, p.dir(), p.tmax);
                          else if (!p.has(kPathOccluded))  // else already decided elsewhere
                            batch.addOccluded(uint32_t(i), p.origin, p.dir(), p.tmax);
                        }
                        geometry.trace(batch);
                        closest += batch.closestCount();
                        shadow += batch.occludedCount();
                        for (size_t k = 0; k < batch.closestCount(); ++k) {
                          if (!batch.hitFound(k)) continue;
                          const uint32_t i = batch.closestIndex(k);
                          Path& p = rays[i];
                          if (!(batch.hitDistance(k) < p.tmax)) continue;
                          const TraceHit hit = batch.hit(k);
                          p.tmax = hit.t;
                          p.setHit(rank, instanceOwners.empty() ? 0 : instanceOwners[hit.instance]);
                          if (found)
                            found[i] = hit;  // this trace set tmax: shading need not re-trace
                        }
                        for (size_t k = 0; k < batch.occludedCount(); ++k)
                          if (batch.isOccluded(k)) rays[batch.occludedIndex(k)].set(kPathOccluded);
                      }
                      closestCount += closest;
                      shadowCount += shadow;
                    });
  stats.closestTraces += closestCount;
  stats.occlusionTraces += shadowCount;
  stats.times.trace += secondsSince(start);
}

template void traceLocally<Path8>(const LocalGeometry&, PathQueue<Path8>&, int,
                                  std::span<const uint64_t>, FrameStats&, TraceHit*);
template void traceLocally<Path64>(const LocalGeometry&, PathQueue<Path64>&, int,
                                   std::span<const uint64_t>, FrameStats&, TraceHit*);
template void traceLocally<PathReplay>(const LocalGeometry&, PathQueue<PathReplay>&, int,
                                       std::span<const uint64_t>, FrameStats&, TraceHit*);

}  // namespace ferry
