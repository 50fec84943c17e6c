// Sampling a ray's way through one medium: free-flight distances by delta
// tracking (spectral tracking for chromatic media: Kutz et al. 2017, so a
// different sigma per channel is unbiased) and transmittance by residual
// ratio tracking (or delta tracking, to compare), both stepping against the
// majorant grid cell by cell. A homogeneous medium is sampled in closed
// form (pbrt-v3's HomogeneousMedium: a channel picked uniformly, weighed by
// the average density). `d` is a unit direction; distances are world lengths.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/math.h"
#include "core/random.h"
#include "media/medium.h"

namespace ferry {

// What tracking did (per rank in the frame stats).
struct MediumCounts {
  uint64_t realCollisions = 0;  // absorptions and scatterings sampled
  uint64_t nullCollisions = 0;  // tentative collisions that went on
  uint64_t majorantCells = 0;   // majorant cells stepped through
  void add(const MediumCounts& o) {
    realCollisions += o.realCollisions;
    nullCollisions += o.nullCollisions;
    majorantCells += o.majorantCells;
  }
};

// The random numbers one walk draws: dimensions first, first + 1, ... of
// one vertex's key (counter-based: a walk of any length stays a pure
// function of the key).
class TrackingRandom {
 public:
  TrackingRandom(uint32_t keyHash, uint32_t firstDimension)
      : keyHash_(keyHash), dimension_(firstDimension) {}
  float next() { return random01FromBits(randomBitsFromKeyHash(keyHash_, dimension_++)); }

 private:
  uint32_t keyHash_;
  uint32_t dimension_;
};

// A distance with density rate x exp(-rate x), from u in [0, 1).
inline float exponentialDistance(float u, float rate) {
  return -std::log(1 - u) / rate;
}

// The random key of a ray tracked through one piece of a volume (a brick, a
// cluster of cells): its origin's and direction's bits and the piece's seed,
// so the piece answers a ray the same on every rank, however often asked.
inline uint32_t rayTrackingKey(Vec3f o, Vec3f d, uint32_t seed) {
  uint32_t h = seed;
  for (float f : {o.x, o.y, o.z, d.x, d.y, d.z}) {
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    h = hashCombine(h, bits);
  }
  return h;
}

struct FreeFlight {
  enum class Event : uint8_t { Passed, Scattered, Absorbed };
  Event event = Event::Passed;
  float t = 0;  // where it scattered or was absorbed
  // The path's throughput factor up to there (to tMax when it passed).
  Vec3f weight{1, 1, 1};
  // Radiance the medium emits towards the ray's origin over the segment,
  // already weighed: add it times the path's throughput before the segment.
  Vec3f emitted{0, 0, 0};
};

FreeFlight sampleFreeFlight(const Medium& medium, Vec3f o, Vec3f d, float tMin, float tMax,
                            TrackingRandom& random, MediumCounts& counts);

enum class TransmittanceEstimator : uint8_t {
  Ratio,  // residual ratio tracking: each majorant cell's smallest density in
          // closed form, the rest a product of null-collision probabilities
  Delta   // delta tracking: 0 at the first real collision, else 1 (a baseline)
};

// An unbiased estimate of the transmittance along [tMin, tMax].
Vec3f transmittance(const Medium& medium, Vec3f o, Vec3f d, float tMin, float tMax,
                    TransmittanceEstimator estimator, TrackingRandom& random, MediumCounts& counts);

}  // namespace ferry
