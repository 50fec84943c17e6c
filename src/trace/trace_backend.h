// What the renderer and the distributed traversal ask of the geometry a rank
// holds: the trace backend. Like pbrt-v4's WavefrontAggregate, the backend
// traces a wavefront's queue of compact paths itself, so every virtual call
// covers a whole wavefront (or a shading batch), never one ray, and the
// backend writes each ray once in whatever layout its tracer reads.
//
// Two implementations: Embree (embree_backend.h, what `ferry` uses) and a
// plain C++ reference (reference_backend.h, for tests). Nothing here names
// Embree; its types stay in embree_backend.cpp.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include "core/math.h"
#include "path/path.h"
#include "scene/motion.h"
#include "scene/shape.h"

namespace ferry {

struct TraceRay {
  Vec3f origin;
  Vec3f direction;
  float tnear = 0;
  float tmax = kInfinity;
  float time = 0;  // motion time u in [0, 1] (scene/motion.h)
};

struct TraceHit {
  float t = kInfinity;
  int32_t instance = -1;   // index into Scene::instances
  int32_t slot = -1;       // in the instance's object: its meshes, then its geometries
  uint32_t primitive = 0;  // triangle within the mesh, or the shape's primitive
  float u = 0, v = 0;      // barycentrics of vertices 1 and 2, or the shape's (u, v)
  float time = 0;          // the ray's motion time (where a moving instance was)

  bool valid() const { return instance >= 0; }
};

// A ray shading re-traces to recover its hit: the path's origin and direction
// and the closest-hit distance recorded in it (Path::tmax).
struct RetraceRay {
  Vec3f origin;
  Vec3f direction;
  float tmax = 0;
  float time = 0;  // motion time u
};

// Queries one trace of a queue made, for FrameStats (trace/ knows no render stats).
struct TraceCounts {
  uint64_t closest = 0;    // closest-hit queries (paths)
  uint64_t occlusion = 0;  // occlusion queries (shadow rays not already occluded)
  ShapeWork shapes;        // what crossing other kinds of geometry cost (volumes' tracking)
};

// Bytes the backend holds for its acceleration structures (and any copy of
// scene data it had to make), now and at its peak (during the build).
struct BackendBytes {
  int64_t now = 0;
  int64_t peak = 0;
};

// What the backend built over the instances it was given: objects (an object
// placed at the top level counts), instances, and of the objects how many sit
// at the top level, without an instance level.
struct BuiltCounts {
  uint64_t objects = 0;
  uint64_t instances = 0;
  uint64_t topLevelObjects = 0;
};

// Which objects get an instance level. An object this rank places exactly
// once, untransformed, instances nothing: with Shared its meshes join the top
// level, as a production renderer keeps unique geometry (saves every ray an
// instance transform and a second BVH root; docs/performance.md). Instancing
// is never flattened: an object's triangles exist once however often it is
// placed. Hits name the same (instance, mesh slot) either way.
enum class Instancing : uint8_t {
  Shared,  // objects placed more than once, or transformed; unique geometry at the top level
  Always   // every object, even one placed once
};

// A backend failed (could not build, or reported an error while tracing).
// Thrown on the thread that called the backend.
class TraceError : public std::runtime_error {
 public:
  explicit TraceError(const std::string& message) : std::runtime_error(message) {}
};

class TraceBackend {
 public:
  virtual ~TraceBackend() = default;

  // Traces every path of `paths` here, in parallel over batches: marks it
  // traced on `rank` (Path::markTraced); a path's closest hit, when closer
  // than its tmax, becomes its tmax and Path::setHit(rank,
  // instanceOwners[instance]) (the mask layouts record those owners, every
  // rank holding the content; this rank alone when the table is empty; the
  // replay layout records the rank); a shadow ray not yet kPathOccluded gets
  // kPathOccluded when anything blocks it. With `kept` (paths.size()
  // entries), kept[i] becomes the hit that set path i's tmax in this call,
  // else an invalid hit. A path's motion time is times.of(pixel). Throws
  // TraceError, after the whole queue, when the tracer reported an error.
  virtual TraceCounts trace(PathQueue<Path8>& paths, int rank,
                            std::span<const uint64_t> instanceOwners, std::span<TraceHit> kept = {},
                            const PathTimes& times = {}) const = 0;
  virtual TraceCounts trace(PathQueue<Path64>& paths, int rank,
                            std::span<const uint64_t> instanceOwners, std::span<TraceHit> kept = {},
                            const PathTimes& times = {}) const = 0;
  virtual TraceCounts trace(PathQueue<PathReplay>& paths, int rank,
                            std::span<const uint64_t> instanceOwners, std::span<TraceHit> kept = {},
                            const PathTimes& times = {}) const = 0;
  virtual TraceCounts trace(PathQueue<PathProbe>& paths, int rank,
                            std::span<const uint64_t> instanceOwners, std::span<TraceHit> kept = {},
                            const PathTimes& times = {}) const = 0;

  // Shading's re-trace, on the calling thread: hits[i] becomes the hit whose
  // distance rays[i].tmax records (the same hit, bit for bit, that the trace
  // which recorded it found), or an invalid hit when it is not found again.
  // How far past tmax to search is the backend's business: its tracer's
  // tolerance (docs/architecture.md, "Re-trace margin").
  virtual void retrace(std::span<const RetraceRay> rays, std::span<TraceHit> hits) const = 0;

  // One ray (tests and pictures; the renderer uses the calls above).
  virtual TraceHit intersect(const TraceRay& ray) const = 0;
  virtual bool occluded(const TraceRay& ray) const = 0;

  virtual Box3f bounds() const = 0;
  virtual BackendBytes bytes() const = 0;
  virtual BuiltCounts built() const = 0;
};

}  // namespace ferry
