// The ray-guided partitioner's sample (partition/ray_sample.h), traced
// through the whole scene with Embree. Deterministic from the seed: the same
// scene and seed give the same rays, bit for bit, whatever the thread count.
//
// The sample must not be the views being evaluated (issue 16), so it is made
// from the scene's box alone. Each path:
//   1. an outer ray: from a random point on the sphere around the scene's box
//      towards a random point inside the box (a camera far outside, as an
//      overview sees the content);
//   2. a camera ray: from a random point on the outer ray's free stretch
//      inside the box (free space, where a camera can stand, weighted by how
//      visible it is from outside) in a uniformly random direction;
//   3. from each hit up to `depth` bounces: a shadow ray and a continuation,
//      both cosine-distributed about the geometric normal facing the ray
//      (diffuse scattering and light from a sky: the rays a path tracer makes).
// Every ray is kept as its segment up to its first hit (shadow rays too: a
// shadow ray stops at its first blocker).
#pragma once

#include <cstdint>

#include "partition/partitioner.h"
#include "partition/ray_sample.h"

namespace ferry {

struct Scene;

struct RaySamplerOptions {
  uint32_t seed = 1;
  uint64_t paths = 65536;
  int depth = 3;  // bounces after the camera ray's hit
};

RaySample sampleSceneRays(const Scene& scene, const RaySamplerOptions& options);

// `options` with the sample the ray-guided partitioner needs, made from
// `scene` (its seed and rayPaths); other partitioners' options as they are.
PartitionerOptions withRaySample(const Scene& scene, PartitionerOptions options);

}  // namespace ferry
