// Where rays go between two shading steps. The renderer hands a wavefront of
// new rays to a RayTraversal and gets back the rays this rank must shade, each
// with its closest hit recorded as tmax and hit owners (or, for shadow rays,
// whether an occluder was found).
//
// LocalTraversal is the one-rank case: everything is here, so a ray is traced
// once. The distributed traversal (src/distributed) forwards rays between ranks by
// proxies; the renderer does not know which one it has.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/clock.h"
#include "render/render_stats.h"
#include "trace/path.h"
#include "trace/trace_backend.h"

namespace ferry {

template <typename Path>
class RayTraversal {
 public:
  virtual ~RayTraversal() = default;
  // Proxy-guided primary rays: whether this rank generates the camera path of `pixel`.
  virtual bool keepsPrimary(uint32_t pixel, const TraceRay& ray, FrameStats& stats) const = 0;
  // Whether every camera path is generated here (one rank): then the renderer
  // skips keepsPrimary and writes the camera rays straight into the queue.
  virtual bool keepsAllPrimaries() const { return false; }
  // Traces all of `rays` (new rays, made on this rank) to completion; on
  // return `rays` holds exactly the rays this rank must shade, and `hits` one
  // entry per ray: its closest hit when this rank found it in this traversal
  // (so shading need not re-trace it), else an invalid hit (re-trace).
  virtual void traverse(PathQueue<Path>& rays, std::vector<TraceHit>& hits,
                        ExchangeCounters& exchange, FrameStats& stats) = 0;
  // True while any rank still has rays (a collective in the distributed case).
  virtual bool anyRaysLeft(size_t localRays) = 0;
};

// TraceBackend::trace on this rank, its queries and time added to `stats`.
template <typename Path>
void traceCounted(const TraceBackend& backend, PathQueue<Path>& rays, int rank,
                  std::span<const uint64_t> instanceOwners, std::span<TraceHit> kept,
                  FrameStats& stats) {
  const auto start = Clock::now();
  const TraceCounts counts = backend.trace(rays, rank, instanceOwners, kept);
  stats.closestTraces += counts.closest;
  stats.occlusionTraces += counts.occlusion;
  stats.times.trace += secondsSince(start);
}

template <typename Path>
class LocalTraversal final : public RayTraversal<Path> {
 public:
  explicit LocalTraversal(const TraceBackend& backend) : backend_(backend) {}
  bool keepsPrimary(uint32_t, const TraceRay&, FrameStats&) const override { return true; }
  bool keepsAllPrimaries() const override { return true; }
  // Every ray is traced once, here: every hit is known.
  void traverse(PathQueue<Path>& rays, std::vector<TraceHit>& hits, ExchangeCounters&,
                FrameStats& stats) override {
    hits.resize(rays.size());
    traceCounted(backend_, rays, 0, {}, hits, stats);
  }
  bool anyRaysLeft(size_t localRays) override { return localRays > 0; }

 private:
  const TraceBackend& backend_;
};

}  // namespace ferry
