// Where rays go between two shading steps. The renderer hands a wavefront of
// new rays to a RayTraversal and gets back the rays this rank must shade, each
// with its closest hit recorded as tmax and hit owners (or, for shadow rays,
// whether an occluder was found).
//
// LocalTraversal is the one-rank case: everything is here, so a ray is traced
// once. The distributed traversal (src/dist) forwards rays between ranks by
// proxies; the renderer does not know which one it has.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "render/render_stats.h"
#include "trace/local_geometry.h"

namespace ferry {

template <typename Path>
class RayTraversal {
 public:
  virtual ~RayTraversal() = default;
  virtual int rank() const = 0;
  virtual int rankCount() const = 0;
  // Proxy-guided primary rays: whether this rank generates the camera path of `pixel`.
  virtual bool keepsPrimary(uint32_t pixel, const TraceRay& ray, FrameStats& stats) const = 0;
  // Traces all of `rays` (new rays, made on this rank) to completion; on
  // return `rays` holds exactly the rays this rank must shade.
  virtual void traverse(std::vector<Path>& rays, ExchangeCounters& exchange, FrameStats& stats) = 0;
  // True while any rank still has rays (a collective in the distributed case).
  virtual bool anyRaysLeft(size_t localRays) = 0;
};

// Marks a path's closest hit on this rank or its shadow-ray occlusion, using
// batched Embree queries, and records the rank as visited (Path::markTraced).
// A closer hit is recorded by Path::setHit: the mask layouts take the hit
// owners from `instanceOwners[instance]` (every rank holding that content,
// for replication; this rank alone when the table is empty), the replay
// layout records this rank.
template <typename Path>
void traceLocally(const LocalGeometry& geometry, std::vector<Path>& rays, int rank,
                  std::span<const uint64_t> instanceOwners, FrameStats& stats);

template <typename Path>
class LocalTraversal final : public RayTraversal<Path> {
 public:
  explicit LocalTraversal(const LocalGeometry& geometry) : geometry_(geometry) {}
  int rank() const override { return 0; }
  int rankCount() const override { return 1; }
  bool keepsPrimary(uint32_t, const TraceRay&, FrameStats&) const override { return true; }
  void traverse(std::vector<Path>& rays, ExchangeCounters&, FrameStats& stats) override {
    traceLocally(geometry_, rays, 0, {}, stats);
  }
  bool anyRaysLeft(size_t localRays) override { return localRays > 0; }

 private:
  const LocalGeometry& geometry_;
};

}  // namespace ferry
