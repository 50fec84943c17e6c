// The ray-guided partitioner's sample (partition/ray_sample.h), traced
// through the whole scene with Embree. Deterministic from the seed: the same
// scene and seed give the same rays, bit for bit, whatever the thread count.
//
// Made from the scene's box alone, never from its named views: an outer ray
// from the sphere around the box, a camera ray from its free stretch inside,
// then up to `depth` diffuse bounces with a shadow ray each; every ray kept
// as its segment up to its first hit (docs/partitioning.md, "The ray-guided
// partitioner").
#pragma once

#include <cstdint>

#include "partition/ray_sample.h"

namespace ferry {

struct Scene;

struct RaySamplerOptions {
  uint32_t seed = 1;
  uint64_t paths = 65536;
  int depth = 3;  // bounces after the camera ray's hit
};

RaySample sampleSceneRays(const Scene& scene, const RaySamplerOptions& options);

}  // namespace ferry
