// The compact path: the paper's 36-byte unit of work (Section 5.1), the same
// struct in the queues, on the wire between ranks, and in shading.
//
// It is deliberately a *ray plus history*, not a hit record: the closest hit
// is remembered only as `tmax` and the ranks that own it (a mask, or in the
// replay layout the one rank that found it), and the rank that shades
// re-traces the ray to recover the full hit (unless that rank found the hit
// itself in this wavefront: ray_traversal.h, --retrace).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/half.h"
#include "core/math.h"
#include "core/octahedral.h"

namespace ferry {

enum PathFlags : uint32_t {
  kPathShadow = 1u << 0,         // a shadow ray carrying its unoccluded contribution
  kPathOccluded = 1u << 1,       // shadow ray: an occluder was found
  kPathAfterSpecular = 1u << 2,  // previous vertex was a delta lobe (or the camera):
                                 // emission hit next counts (no light sample covered it)
  kPathTraversed = 1u << 3,      // traversal is complete: sent to a rank only to be shaded
  kPathReply = 1u << 4,          // broadcast mode: a copy returning its result to its origin
  kPathLight = 1u << 5,          // a light path (pixel() is its light path index), or its
                                 // shadow ray to the camera (the pixel is where origin projects)
  kPathFlagMask = 0x3fu,
};
constexpr int kPixelBits = 26;  // 67 M pixels, e.g. 8192 x 8192
constexpr uint32_t kMaxPixels = 1u << kPixelBits;

// What every layout shares: the ray, its throughput, the previous vertex's
// BSDF density, and pixel + flags (32 bytes). Each layout adds its rank
// history and `lightRatio`: for light tracing (render/path_shading.h,
// "light paths"), packed as bsdfDensity, a camera path carries the running
// ratio of a light path's density of its vertices to its own (what its MIS
// weights against a light path connected to the camera need), a light path
// the running sum of squared ratios the other way; 0 without light paths.
// (It is not in PathCore: a base's tail padding is not reused, and Path8
// would grow to 40 bytes.)
struct PathCore {
  Vec3f origin;
  uint32_t direction;  // octahedral (core/octahedral.h): 2 x 16 bits
  // The density (solid angle) with which the previous vertex's BSDF sampled
  // this direction, packed to 16 bits: a path that finds an emitter weighs
  // the emission against the light sample that could also have found it
  // (MIS). Unused (0) for camera rays, delta lobes (kPathAfterSpecular) and
  // shadow rays.
  // Its sign bit (densities are positive) is kSkyByMis.
  uint16_t bsdfDensity;
  half throughput[3];
  float tmax;
  uint32_t pixelAndFlags;  // pixel id in the high 26 bits, flags in the low 6

  uint32_t pixel() const { return pixelAndFlags >> (32 - kPixelBits); }
  uint32_t flags() const { return pixelAndFlags & kPathFlagMask; }
  bool has(PathFlags f) const { return (pixelAndFlags & f) != 0; }
  bool isShadow() const { return has(kPathShadow); }
  bool isTraversed() const { return has(kPathTraversed); }
  void set(PathFlags f) { pixelAndFlags |= f; }
  void setPixelAndFlags(uint32_t pixel, uint32_t flags) {
    pixelAndFlags = (pixel << (32 - kPixelBits)) | (flags & kPathFlagMask);
  }

  [[gnu::always_inline]] Vec3f dir() const { return decodeOctahedral(direction); }
  [[gnu::always_inline]] Vec3f weight() const { return unpack(offsetof(PathCore, throughput)); }
  float bsdfPdf() const { return unpackDensity(bsdfDensity & uint16_t(~kSkyByMis)); }
  // The previous vertex's light sample drew a constant environment over the
  // whole sphere (the vertex transmits, or lies in a medium) and weighed it
  // by MIS: an escaped path then weighs the sky against that sample.
  static constexpr uint16_t kSkyByMis = 0x8000;
  bool skyByMis() const { return (bsdfDensity & kSkyByMis) != 0; }
  void setSkyByMis() { bsdfDensity |= kSkyByMis; }
  // The direction is quantized here, when the ray is made, so every rank
  // traces exactly the same ray whatever the rank count; returns dir().
  [[gnu::always_inline]] Vec3f setDir(Vec3f d) {
    direction = encodeOctahedral(d);
    return decodeOctahedral(direction);
  }
  [[gnu::always_inline]] void setWeight(Vec3f w) { floatsToHalves3(w.x, w.y, w.z, throughput); }
  // Both at once (what a new ray needs); returns dir().
  [[gnu::always_inline]] Vec3f setDirAndWeight(Vec3f d, Vec3f w) {
    setWeight(w);
    return setDir(d);
  }
  // Stores `pdf` as packed (and returns what was stored, which is what the
  // path will read back: both MIS weights use that value).
  float setBsdfPdf(float pdf) {
    bsdfDensity = packDensity(pdf);
    return bsdfPdf();
  }

 private:
  // The three halves at `offset` and the two bytes after them (still inside
  // the path: tmax follows throughput) in one load.
  [[gnu::always_inline]] Vec3f unpack(size_t offset) const {
    uint64_t packed;
    std::memcpy(&packed, reinterpret_cast<const unsigned char*>(this) + offset, 8);
    Vec3f v;
    halves3ToFloats(packed, &v.x);
    return v;
  }
};
static_assert(sizeof(PathCore) == 32);

// The mask layouts: RankMask is uint8_t (up to 8 ranks, 36 bytes) or
// uint64_t (up to 64 ranks, 56 bytes).
template <typename RankMask>
struct PathT : PathCore {
  RankMask visited;     // ranks this ray has been traced on
  RankMask hitOwners;   // ranks holding the content of the closest hit so far (0: no hit)
  uint16_t lightRatio;  // see PathCore

  using Mask = RankMask;
  static constexpr bool kReplay = false;
  static constexpr bool kProbes = false;

  bool hasHit() const { return hitOwners != 0; }
  void clearHistory() {
    visited = 0;
    hitOwners = 0;
  }
  // Traced on `rank` (local tracing marks every ray it traces).
  void markTraced(int rank) { visited |= RankMask(RankMask(1) << rank); }
  // The closest hit so far was found on `rank`, in content `owners` hold (a mask up to 64 ranks).
  void setHit(int rank, uint64_t owners) {
    hitOwners = owners ? RankMask(owners) : RankMask(RankMask(1) << rank);
  }
};

// The replay layout, for any rank count (the paper's Section 3.3 "replay"):
// instead of a mask of visited ranks the ray keeps only the rank that
// generated it; any rank recomputes the visited set by re-running the
// forwarding decisions from there (distributed/forwarding.h: replayWalk). The hit is
// kept as the one rank that found it, which therefore holds it (the mask
// layouts keep every owner of the hit content, so a replica may shade; here
// the finished ray goes to that one rank). Two 16-bit rank ids replace the
// two masks, so the path is 40 bytes (36, the paper's compact size, before light tracing
// needed lightRatio) at any rank
// count up to 65535 (0xffff means "none"). No more state is needed: the
// visited ranks are a prefix of the ray's walk through the proxies, which
// does not depend on tmax (see replayWalk), so the proxy distance reached so
// far need not travel with the ray.
struct PathReplay : PathCore {
  static constexpr uint16_t kNoRank = 0xffff;
  uint16_t generatingRank;  // where the ray was made and first traced (kNoRank: not yet traced)
  uint16_t hitRank;         // the rank that found the closest hit so far (kNoRank: no hit)
  uint16_t lightRatio;      // see PathCore

  static constexpr bool kReplay = true;
  static constexpr bool kProbes = false;

  bool hasHit() const { return hitRank != kNoRank; }
  void clearHistory() {
    generatingRank = kNoRank;
    hitRank = kNoRank;
  }
  // The first rank that traces a ray is the one that made it (local first).
  void markTraced(int rank) {
    if (generatingRank == kNoRank) generatingRank = uint16_t(rank);
  }
  void setHit(int rank, uint64_t) { hitRank = uint16_t(rank); }
};

// The probe layout, for scenes whose subsurface materials are sampled by
// pbrt's BSSRDF (render/path_shading.cpp, "Subsurface probes"): the replay
// layout and what a probe needs on its way from the point where light
// entered the material to the point where it leaves, through ranks that may
// not hold the material: the entry point and its normal (the probe's
// frame), the segment, the material's probe id, and how many of its
// surfaces the probe has found (80 bytes).
struct PathProbe : PathReplay {
  enum Phase : uint8_t {
    kNotProbing = 0,  // an ordinary path
    kCounting = 1,    // crossing the probe segment, counting the material's surfaces
    kReturning = 2,   // crossing it again to the surface chosen among them
  };
  Vec3f probeEntry;        // where light entered
  uint32_t probeNormal;    // the entry's shading normal, octahedral
  Vec3f probeStart;        // the segment: its start, and its end at probeStart +
  float probeLength;       // dir() * probeLength (the first ray's tmax)
  uint32_t probeMaterial;  // the material's SubsurfaceModel::probeId
  uint8_t probePhase;
  uint8_t probeFound;  // surfaces of the material found (counting), or in all (returning)
  uint8_t probeSkip;   // returning: surfaces to pass before the chosen one
  uint8_t probeUnused;

  static constexpr bool kProbes = true;
  bool probing() const { return probePhase != kNotProbing; }
  void clearHistory() {
    PathReplay::clearHistory();
    probePhase = kNotProbing;
  }
};

using Path8 = PathT<uint8_t>;
using Path64 = PathT<uint64_t>;
static_assert(sizeof(Path8) == 36, "the paper's compact path is 36 bytes up to 8 ranks");
static_assert(sizeof(Path64) == 56, "the wide path (up to 64 ranks) is 56 bytes");
static_assert(sizeof(PathReplay) == 40,
              "the replay path (any rank count) is 40 bytes: two 16-bit rank ids instead of "
              "masks, and lightRatio (docs/architecture.md: the path's size)");
static_assert(sizeof(PathProbe) == 80, "the probe path is the replay path and 40 bytes");
static_assert(std::is_trivially_copyable_v<Path8> && std::is_trivially_copyable_v<Path64> &&
                  std::is_trivially_copyable_v<PathReplay> &&
                  std::is_trivially_copyable_v<PathProbe>,
              "paths are sent over MPI as bytes");

// The medium a camera path travels in: in a scene with participating media
// (which takes no light paths: render/path_shading.h), the 16 bits of
// lightRatio hold instead its index in Scene::media plus 1 (0: none), so
// the medium costs the path no byte. Shadow rays carry none: their
// transmittance is estimated where they are made.
template <typename Path>
int32_t pathMedium(const Path& p) {
  return int32_t(p.lightRatio) - 1;
}
template <typename Path>
void setPathMedium(Path& p, int32_t medium) {
  p.lightRatio = uint16_t(medium + 1);
}

// A wavefront's queue of paths. Every path in a queue is written before it is
// read, so growing a queue need not zero it (value-initializing the new paths
// would be a memset of the whole image's queue per sample): the allocator
// leaves default-constructed paths uninitialized. Paths are aggregates of trivially
// copyable parts (implicit-lifetime types), so the storage is their object.
template <typename T>
struct UninitializedAllocator : std::allocator<T> {
  using value_type = T;
  template <typename U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <typename U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) > 0) ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <typename Path>
using PathQueue = std::vector<Path, UninitializedAllocator<Path>>;

// A wavefront's rays, each kind in its own queue: paths (their closest hit
// is wanted; shading continues them) and shadow rays (any hit decides;
// shading adds the light of the unoccluded ones). Stages read and write the
// kind they handle, so no stage sorts rays by flag. The rays still carry
// kPathShadow: on the wire both kinds travel as one queue (the distributed
// traversal exchanges them together and sorts what it returns by kind), and
// the trace asks each ray the question its kind needs.
template <typename Path>
struct RayQueues {
  PathQueue<Path> paths;
  PathQueue<Path> shadowRays;

  size_t size() const { return paths.size() + shadowRays.size(); }
  void clear() {
    paths.clear();
    shadowRays.clear();
  }
};

}  // namespace ferry
