// A sample of rays spread over a scene, what the ray-guided partitioner
// (ray_guided_partitioner.h) weighs its splits with: each ray a segment from
// its origin to its first hit in the whole scene (or to where it leaves the
// scene's box). The partitioner needs only the segments: which units' boxes
// a segment passes is a question of boxes, answered here in partition/; the
// hits come from a tracer (partition/ray_sampler.h makes the sample with Embree).
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"

namespace ferry {

struct RaySegment {
  Vec3f origin;
  Vec3f direction;  // unit length
  float tmax = kInfinity;
};

struct RaySample {
  std::vector<RaySegment> rays;
  uint64_t paths = 0;  // the sample's paths (each several rays)
  uint32_t seed = 0;
  double seconds = 0;  // making it: building the tracer and tracing
};

}  // namespace ferry
