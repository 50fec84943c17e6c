// The compact path: the paper's 36-byte unit of work (Section 5.1), the same
// struct in the queues, on the wire between ranks, and in shading.
//
// It is deliberately a *ray plus history*, not a hit record: the closest hit
// is remembered only as `tmax` and the mask of ranks that own it, and the
// rank that shades re-traces the ray to recover the full hit.
#pragma once

#include <cstdint>
#include <type_traits>

#include "core/half.h"
#include "core/math.h"

namespace ferry {

enum PathFlags : uint32_t {
  kPathShadow = 1u << 0,          // a shadow ray carrying its unoccluded contribution
  kPathOccluded = 1u << 1,        // shadow ray: an occluder was found
  kPathAfterSpecular = 1u << 2,   // previous vertex was a delta lobe (or the camera):
                                  // emission hit next counts (no light sample covered it)
  kPathTraversed = 1u << 3,       // traversal is complete: sent to a rank only to be shaded
  kPathReply = 1u << 4,           // broadcast mode: a copy returning its result to its origin
  kPathFlagMask = 0x3fu,
};
constexpr int kPixelBits = 26;  // 67 M pixels, e.g. 8192 x 8192
constexpr uint32_t kMaxPixels = 1u << kPixelBits;

// RankMask is uint8_t (up to 8 ranks, 36 bytes) or uint64_t (up to 64 ranks).
template <typename RankMask>
struct PathT {
  Vec3f origin;
  half direction[3];
  half throughput[3];
  float tmax;
  uint32_t pixelAndFlags;  // pixel id in the high 26 bits, flags in the low 6
  RankMask visited;        // ranks this ray has been traced on
  RankMask hitOwners;      // ranks holding the content of the closest hit so far (0: no hit)

  using Mask = RankMask;

  uint32_t pixel() const { return pixelAndFlags >> (32 - kPixelBits); }
  uint32_t flags() const { return pixelAndFlags & kPathFlagMask; }
  bool has(PathFlags f) const { return (pixelAndFlags & f) != 0; }
  bool isShadow() const { return has(kPathShadow); }
  bool hasHit() const { return hitOwners != 0; }
  void set(PathFlags f) { pixelAndFlags |= f; }
  void setPixelAndFlags(uint32_t pixel, uint32_t flags) {
    pixelAndFlags = (pixel << (32 - kPixelBits)) | (flags & kPathFlagMask);
  }

  Vec3f dir() const {
    return {halfToFloat(direction[0]), halfToFloat(direction[1]), halfToFloat(direction[2])};
  }
  Vec3f weight() const {
    return {halfToFloat(throughput[0]), halfToFloat(throughput[1]), halfToFloat(throughput[2])};
  }
  // The direction is quantized here, when the ray is made, so every rank
  // traces exactly the same ray whatever the rank count.
  void setDir(Vec3f d) {
    direction[0] = floatToHalf(d.x);
    direction[1] = floatToHalf(d.y);
    direction[2] = floatToHalf(d.z);
  }
  void setWeight(Vec3f w) {
    throughput[0] = floatToHalf(w.x);
    throughput[1] = floatToHalf(w.y);
    throughput[2] = floatToHalf(w.z);
  }
};

using Path8 = PathT<uint8_t>;
using Path64 = PathT<uint64_t>;
static_assert(sizeof(Path8) == 36, "the paper's compact path is 36 bytes up to 8 ranks");
static_assert(sizeof(Path64) == 48, "the wide path (up to 64 ranks) is 48 bytes");
static_assert(std::is_trivially_copyable_v<Path8> && std::is_trivially_copyable_v<Path64>,
              "paths are sent over MPI as bytes");

}  // namespace ferry
