// How a backend traces a wavefront's queue (TraceBackend::trace), written
// once for every backend so they share its semantics: batches of closest-hit
// and occlusion queries in queue order, built, traced and applied on the
// worker thread that owns them (no whole-wavefront arrays, no serial pass).
// Included by the backends' .cpp files only.
//
// A backend supplies its Batch type (its ray layout: each ray is written once,
// in the form its tracer reads, and answered in place) with
//   kCapacity, clear(),
//   addClosest(index, origin, direction, tmax, time), addOccluded(...),
//   closestCount(), occludedCount(), closestIndex(k), occludedIndex(k),
//   hitFound(k), hitDistance(k), hit(k) (a TraceHit), isOccluded(k),
//   shapeWork() (what its shapes' crossings cost since clear()),
// and a function that traces one batch's two lists.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <mutex>
#include <span>

#include "core/error.h"
#include "path/path.h"
#include "trace/trace_backend.h"

namespace ferry {

template <typename Batch, typename Path, typename TraceBatch>
TraceCounts traceQueueInBatches(PathQueue<Path>& paths, int rank,
                                std::span<const uint64_t> instanceOwners, std::span<TraceHit> kept,
                                const PathTimes& times, const TraceBatch& traceBatch) {
  FERRY_CHECK(kept.empty() || kept.size() == paths.size());
  TraceHit* found = kept.empty() ? nullptr : kept.data();
  constexpr size_t kBatch = Batch::kCapacity;
  std::atomic<uint64_t> closestCount{0}, shadowCount{0};
  std::mutex workMutex;
  ShapeWork work;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, paths.size(), kBatch),
                    [&](const tbb::blocked_range<size_t>& range) {
                      Batch batch;
                      uint64_t closest = 0, shadow = 0;
                      ShapeWork mine;
                      for (size_t begin = range.begin(); begin < range.end(); begin += kBatch) {
                        const size_t n = std::min(kBatch, range.end() - begin);
                        batch.clear();
                        for (size_t i = begin; i < begin + n; ++i) {
                          Path& p = paths[i];
                          p.markTraced(rank);
                          if (found) found[i] = TraceHit{};
                          const float time = times.of(p.pixel());
                          if (!p.isShadow())
                            batch.addClosest(uint32_t(i), p.origin, p.dir(), p.tmax, time);
                          else if (!p.has(kPathOccluded))  // else already decided elsewhere
                            batch.addOccluded(uint32_t(i), p.origin, p.dir(), p.tmax, time);
                        }
                        traceBatch(batch);
                        mine.add(batch.shapeWork());
                        closest += batch.closestCount();
                        shadow += batch.occludedCount();
                        for (size_t k = 0; k < batch.closestCount(); ++k) {
                          if (!batch.hitFound(k)) continue;
                          const uint32_t i = batch.closestIndex(k);
                          Path& p = paths[i];
                          if (!(batch.hitDistance(k) < p.tmax)) continue;
                          const TraceHit hit = batch.hit(k);
                          p.tmax = hit.t;
                          p.setHit(rank, instanceOwners.empty() ? 0 : instanceOwners[hit.instance]);
                          if (found)
                            found[i] = hit;  // this trace set tmax: shading need not re-trace
                        }
                        for (size_t k = 0; k < batch.occludedCount(); ++k)
                          if (batch.isOccluded(k)) paths[batch.occludedIndex(k)].set(kPathOccluded);
                      }
                      closestCount += closest;
                      shadowCount += shadow;
                      const std::lock_guard<std::mutex> lock(workMutex);
                      work.add(mine);
                    });
  return {closestCount.load(), shadowCount.load(), work};
}

}  // namespace ferry
