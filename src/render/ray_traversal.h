// Where rays go between two shading steps. The renderer hands a wavefront of
// new rays to a RayTraversal and gets back the rays this rank must shade, each
// with its closest hit recorded as tmax and hit owners (or, for shadow rays,
// whether an occluder was found).
//
// LocalTraversal is the one-rank case: everything is here, so a ray is traced
// once. The distributed traversal (src/dist) forwards rays between ranks by
// proxies; the renderer does not know which one it has.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "render/render_stats.h"
#include "trace/local_geometry.h"
#include "trace/path.h"

namespace ferry {

// The camera ray of a pixel for the current sample.
using CameraRayOf = std::function<TraceRay(uint32_t pixel)>;

template <typename Path>
class RayTraversal {
 public:
  virtual ~RayTraversal() = default;
  virtual int rank() const = 0;
  virtual int rankCount() const = 0;
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

// Marks a path's closest hit on this rank or its shadow-ray occlusion, using
// batched Embree queries, and records the rank as visited (Path::markTraced).
// A closer hit is recorded by Path::setHit: the mask layouts take the hit
// owners from `instanceOwners[instance]` (every rank holding that content,
// for replication; this rank alone when the table is empty), the replay
// layout records this rank. With `hits` (rays.size() entries), hits[i]
// becomes the hit that set ray i's tmax here, or an invalid hit when this
// trace did not set it.
template <typename Path>
void traceLocally(const LocalGeometry& geometry, PathQueue<Path>& rays, int rank,
                  std::span<const uint64_t> instanceOwners, FrameStats& stats,
                  TraceHit* hits = nullptr);

// The query with which shading re-traces a path whose hit it does not have:
// Embree accepts a hit only somewhat inside tfar, with an error that scales
// with the coordinates, not with t (measured: tfar = t, t + 1e-6 relative, or
// t * 1.001 at t = 0.016 in a 555-unit box can all miss it), so it searches
// past tmax by a margin of both kinds; nothing closer than the recorded hit
// exists, so the closest hit found is the same one.
inline TraceRay retraceQuery(Vec3f origin, Vec3f direction, float tmax) {
  const float scale = std::max({std::abs(origin.x), std::abs(origin.y), std::abs(origin.z), 1.0f});
  return {origin, direction, 0, tmax * 1.001f + 1e-4f * scale};
}

template <typename Path>
class LocalTraversal final : public RayTraversal<Path> {
 public:
  explicit LocalTraversal(const LocalGeometry& geometry) : geometry_(geometry) {}
  int rank() const override { return 0; }
  int rankCount() const override { return 1; }
  bool keepsAllPrimaries() const override { return true; }
  // Every ray is traced once, here: every hit is known.
  void traverse(RayQueues<Path>& rays, std::vector<TraceHit>& pathHits, ExchangeCounters&,
                FrameStats& stats) override {
    pathHits.resize(rays.paths.size());
    traceLocally(geometry_, rays.paths, 0, {}, stats, pathHits.data());
    traceLocally(geometry_, rays.shadowRays, 0, {}, stats);
  }
  bool anyRaysLeft(size_t localRays) override { return localRays > 0; }

 private:
  const LocalGeometry& geometry_;
};

}  // namespace ferry
