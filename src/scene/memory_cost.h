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
struct Geometry;

struct MemoryCost {
  uint64_t vertices = 0;  // positions
  uint64_t normals = 0;
  uint64_t uvs = 0;
  uint64_t indices = 0;
  uint64_t texels = 0;     // textures' texels and tabulated BSDFs' coefficients
  uint64_t shapes = 0;     // what geometries of other kinds hold (Shape::bytes)
  uint64_t instances = 0;  // instance records (transform, ids) and their Embree instance geometry
  uint64_t accel = 0;      // estimated BVH bytes (bottom level per object, top level per instance)
  uint64_t media = 0;      // participating media (grids, majorants) and their boundary meshes,
                           // which every rank holds whole

  // The mesh arrays alone (what a mesh store keeps out of memory).
  uint64_t meshArrays() const { return vertices + normals + uvs + indices; }
  uint64_t total() const { return meshArrays() + texels + shapes + instances + accel + media; }
  MemoryCost& operator+=(const MemoryCost& o);
  MemoryCost scaled(uint64_t times) const;
};

// The model assumes every object has its own BVH under an instance
// (the Embree backend with Instancing::Always); the default build puts an object a
// rank places once, untransformed, into the top-level BVH, which retains no
// more (tested), so for it the model is an upper bound.
// Calibrated constants: measured with Embree 3.13.5 (Debian, default build
// quality, on an AVX-512 CPU) by src/scene/memory_cost_test.cpp, which
// keeps them honest; docs/memory.md has the measurements. `accel` is what
// Embree's memory monitor counts (its retained bytes after the build; the
// peak during a build is higher, see docs/memory.md).
struct MemoryModel {
  // BVH nodes and triangle leaves per triangle.
  static constexpr double kAccelBytesPerTriangle = 64.0;
  // BVH nodes and leaf references per box of a user geometry (a shape's
  // piece; builtin:fur measured).
  static constexpr double kAccelBytesPerShapeBox = 84.0;
  // Embree's BVH per flat curve segment it traces as its own (oriented
  // boxes; builtin:fur measured, 119.7).
  static constexpr double kAccelBytesPerFlatCurve = 120.0;
  // Fixed BVH bytes per mesh: Embree allocates in blocks, so even a
  // two-triangle mesh retains about one block. Matters only for scenes of many
  // small meshes.
  static constexpr double kAccelBytesPerMesh = 1150.0;
  // Top-level BVH bytes per instance in the instancing scene.
  static constexpr double kAccelBytesPerInstance = 100.0;
  // Ferry's Instance record (52 bytes) plus Embree's instance geometry object
  // (298 bytes, on the heap but not reported by the memory monitor).
  static constexpr double kBytesPerInstanceRecord = 350.0;
};

MemoryCost meshCost(uint64_t vertexCount, uint64_t triangleCount, bool hasNormals, bool hasUvs);
MemoryCost meshCost(const Mesh& mesh);
MemoryCost textureCost(uint64_t texelCount);
MemoryCost textureCost(const Texture& texture);
struct FourierBsdfTable;
MemoryCost bsdfTableCost(const FourierBsdfTable& table);
MemoryCost instanceCost(uint64_t instanceCount);
// A geometry of another kind: its shape's bytes, and a BVH per traversal box
// (a primitive's pieces; Embree builds it over the pieces' boxes). A
// released one costs nothing.
MemoryCost geometryCost(const Geometry& geometry);
// A geometry of `boxes` traversal boxes whose shape holds `bytes` (with its BVH).
// `boxes` what Embree bounds (user geometry pieces, or flat curve segments
// at kAccelBytesPerFlatCurve a box).
MemoryCost shapeCost(uint64_t boxes, uint64_t bytes,
                     double accelBytesPerBox = MemoryModel::kAccelBytesPerShapeBox);
// The scene's media and medium boundaries (the boundaries' triangles as a
// mesh's, with their BVH).
struct Scene;
MemoryCost mediaCost(const Scene& scene);

}  // namespace ferry
