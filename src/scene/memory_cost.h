// The memory-cost model: how many bytes a piece of content costs on the rank
// that holds it, including an estimate of Embree's acceleration structure.
// The partitioners split by this cost and `ferry info` prints it; it is
// calibrated against Embree's own memory monitor (docs/memory.md, and the
// test that keeps the two within a stated ratio).
#pragma once

#include <cstdint>

namespace ferry {

struct Mesh;
struct Texture;

struct MemoryCost {
  uint64_t vertices = 0;   // positions
  uint64_t normals = 0;
  uint64_t uvs = 0;
  uint64_t indices = 0;
  uint64_t texels = 0;
  uint64_t instances = 0;  // instance records (transform, ids) and their Embree instance geometry
  uint64_t accel = 0;      // estimated BVH bytes (bottom level per object, top level per instance)

  uint64_t total() const { return vertices + normals + uvs + indices + texels + instances + accel; }
  MemoryCost& operator+=(const MemoryCost& o);
  MemoryCost scaled(uint64_t times) const;
};

// Calibrated constants; see docs/memory.md for how they were measured.
struct MemoryModel {
  // Embree 3 BVH4 over triangle4v primitives, as built at the default quality,
  // retained after the build (the monitor's high-water mark is the peak).
  static constexpr double kAccelBytesPerTriangle = 60.0;
  // Top-level BVH bytes per instance in the instancing scene.
  static constexpr double kAccelBytesPerInstance = 120.0;
  // Instance record plus Embree's RTCGeometry for the instance.
  static constexpr double kBytesPerInstanceRecord = 400.0;
};

MemoryCost meshCost(uint64_t vertexCount, uint64_t triangleCount, bool hasNormals, bool hasUvs);
MemoryCost meshCost(const Mesh& mesh);
MemoryCost textureCost(uint64_t texelCount);
MemoryCost textureCost(const Texture& texture);
MemoryCost instanceCost(uint64_t instanceCount);

}  // namespace ferry
