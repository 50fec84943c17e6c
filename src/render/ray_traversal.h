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
#include <functional>
#include <span>
#include <vector>

#include "core/clock.h"
#include "render/render_stats.h"
#include "trace/path.h"
#include "trace/trace_backend.h"

namespace ferry {

// The camera ray of a pixel for the current sample.
using CameraRayOf = std::function<TraceRay(uint32_t pixel)>;

template <typename Path>
class RayTraversal {
 public:
  virtual ~RayTraversal() = default;
  // Proxy-guided primary rays: sets `pixels` to the pixels of [first, last)
  // whose camera path this rank generates for the current sample, in
  // increasing order; `cameraRay(pixel)` is the pixel's camera ray as the
  // path stores it. Collective when distributed (every rank calls it with
  // the same range). Default: every pixel is this rank's.
  virtual void primaryPixels(uint32_t first, uint32_t last, const CameraRayOf& cameraRay,
                             std::vector<uint32_t>& pixels, FrameStats& stats) {
    (void)cameraRay;
    (void)stats;
    pixels.resize(last - first);
    for (uint32_t p = first; p != last; ++p) pixels[p - first] = p;
  }
  // Whether every camera path is generated here (one rank): then the renderer
  // skips primaryPixels and writes the camera rays straight into the queue.
  virtual bool keepsAllPrimaries() const { return false; }
  // Traces all of `rays` (new paths and shadow rays, made on this rank) to
  // completion; on return `rays` holds exactly the rays this rank must shade,
  // each in the queue of its kind, and `pathHits` one entry per path (in
  // rays.paths order): its closest hit when this rank found it in this
  // traversal (so shading need not re-trace it), else an invalid hit (re-trace).
  virtual void traverse(RayQueues<Path>& rays, std::vector<TraceHit>& pathHits,
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
  bool keepsAllPrimaries() const override { return true; }
  // Every ray is traced once, here: every hit is known.
  void traverse(RayQueues<Path>& rays, std::vector<TraceHit>& pathHits, ExchangeCounters&,
                FrameStats& stats) override {
    pathHits.resize(rays.paths.size());
    traceCounted(backend_, rays.paths, 0, {}, pathHits, stats);
    traceCounted(backend_, rays.shadowRays, 0, {}, {}, stats);
  }
  bool anyRaysLeft(size_t localRays) override { return localRays > 0; }

 private:
  const TraceBackend& backend_;
};

}  // namespace ferry
