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
#include "path/path.h"
#include "render/pixel_set.h"
#include "render/render_stats.h"
#include "trace/trace_backend.h"

namespace ferry {

// The camera rays proxy-guided ownership asks about (primaryPixels).
struct CameraRays {
  // `pixel`'s camera ray for the current sample, as its path stores it.
  std::function<TraceRay(uint32_t pixel)> sample;
  // A pinhole camera's ray through the point (dx, dy) in [0, 1]^2 of
  // `pixel`, where every sample's ray lies; empty for a lens camera. The
  // same function for every call with the same `view`.
  std::function<TraceRay(uint32_t pixel, float dx, float dy)> through;
  uint64_t view = 0;  // names the camera and film window `through` stands for
};

// What the renderer does for a traversal that runs whole samples itself
// (RayTraversal::runsSamples: the overlapped distributed exchange): make
// camera paths, and shade the rays that are ready on this rank, bounce by
// bounce, in whatever order they become ready. The frame buffer sums in
// fixed point, so the order does not change the image.
template <typename Path>
class SampleShading {
 public:
  virtual ~SampleShading() = default;
  // The camera rays of this sample.
  virtual const CameraRays& cameraRays() const = 0;
  // Appends the camera paths of `pixels` to `out`, in that order, and with
  // light paths (render/path_shading.h) theirs after them: any number.
  virtual void cameraPaths(std::span<const uint32_t> pixels, PathQueue<Path>& out,
                           FrameStats& stats) = 0;
  // Shades rays of bounce `bounce` whose traversal ended here: shadow rays
  // add their light, paths are shaded (`hits[i]`: path i's kept hit, or
  // invalid to re-trace). `next` is replaced by the new rays (continuations
  // and shadow rays of bounce + 1). `ready` and `hits` are left unspecified.
  virtual void shade(uint32_t bounce, RayQueues<Path>& ready, std::vector<TraceHit>& hits,
                     RayQueues<Path>& next, FrameStats& stats) = 0;
};

template <typename Path>
class RayTraversal {
 public:
  virtual ~RayTraversal() = default;
  // Whether this traversal runs a whole sample itself (runSample): it then
  // decides when rays are traced, forwarded and shaded, instead of being
  // called once per bounce of a wavefront (traverse).
  virtual bool runsSamples() const { return false; }
  // One sample of the pixels of `set` from camera paths to the last
  // bounce, shading through `shading`. Collective when distributed.
  virtual void runSample(uint32_t sampleIndex, const PixelSet& set, SampleShading<Path>& shading,
                         FrameStats& stats) {
    (void)sampleIndex, (void)set, (void)shading, (void)stats;
  }
  // Proxy-guided primary rays: sets `pixels` to the pixels of `set` whose
  // camera path this rank generates for the current sample, in increasing
  // order. Any rank may start any camera path (the image is the same); the
  // owner of what the ray meets first saves forwards. Collective when
  // distributed (every rank calls it with the same set and rays).
  // Default: every pixel is this rank's.
  virtual void primaryPixels(const PixelSet& set, const CameraRays& cameraRays,
                             std::vector<uint32_t>& pixels, FrameStats& stats) {
    (void)cameraRays;
    (void)stats;
    set.list(pixels);
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
  // Sums `values` element-wise over the ranks, in place (a collective when
  // distributed); true on the one rank that is to use the sums.
  virtual bool sumOverRanks(std::vector<int64_t>& values) {
    (void)values;
    return true;
  }
  // When the rays traced next are (scene/motion.h): the renderer sets it
  // before each sample.
  void setPathTimes(const PathTimes& times) { times_ = times; }

 protected:
  PathTimes times_;
};

// TraceBackend::trace on this rank, its queries and time added to `stats`.
template <typename Path>
void traceCounted(const TraceBackend& backend, PathQueue<Path>& rays, int rank,
                  std::span<const uint64_t> instanceOwners, std::span<TraceHit> kept,
                  const PathTimes& times, FrameStats& stats) {
  const auto start = Clock::now();
  const TraceCounts counts = backend.trace(rays, rank, instanceOwners, kept, times);
  stats.closestTraces += counts.closest;
  stats.occlusionTraces += counts.occlusion;
  // Volumes' tracking happens in the trace (shapes/volume_brick.h).
  stats.mediumRealCollisions += counts.shapes.realCollisions;
  stats.mediumNullCollisions += counts.shapes.nullCollisions;
  stats.mediumMajorantCells += counts.shapes.cells;
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
    traceCounted(backend_, rays.paths, 0, {}, pathHits, this->times_, stats);
    traceCounted(backend_, rays.shadowRays, 0, {}, {}, this->times_, stats);
  }
  bool anyRaysLeft(size_t localRays) override { return localRays > 0; }

 private:
  const TraceBackend& backend_;
};

}  // namespace ferry
