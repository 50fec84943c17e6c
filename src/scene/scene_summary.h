// What `ferry info` reports about a scene: counts and the memory estimate.
// Computed either from a loaded Scene or, for built-ins at large scales, from
// the generator's counts alone, without making any geometry.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/math.h"
#include "scene/memory_cost.h"

namespace ferry {

struct Scene;

struct SceneSummary {
  std::string name;
  uint64_t uniqueMeshes = 0;
  uint64_t geometries = 0;  // of other kinds than triangle meshes (scene/shape.h)
  uint64_t shapePrimitives = 0;
  // Per kind of geometry ("curves", "spheres", "volume-brick"): how many
  // geometries, and their primitives (curve segments, spheres, bricks).
  struct ShapeKindCount {
    uint64_t geometries = 0, primitives = 0;
    bool operator==(const ShapeKindCount&) const = default;
  };
  std::map<std::string, ShapeKindCount> shapeKinds;
  uint64_t volumeBricks = 0;  // geometries that are volumes (shapes/volume_brick.h)
  uint64_t triangles = 0;     // unique: each mesh counted once
  uint64_t vertices = 0;
  uint64_t objects = 0;
  uint64_t instances = 0;
  uint64_t movingInstances = 0;     // that move while the shutter is open (scene/motion.h)
  uint64_t instancedTriangles = 0;  // every instance's triangles
  uint64_t textures = 0;
  uint64_t texels = 0;
  uint64_t suns = 0;
  uint64_t pointLights = 0;   // point and spot lights
  uint64_t environments = 0;  // 0 or 1
  uint64_t emissiveMeshes = 0;
  uint64_t emissiveTriangles = 0;
  uint64_t views = 0;
  // Participating media, each as `ferry info` lists it, and the surfaces
  // that only bound them.
  struct Medium {
    std::string name;
    std::string kind;  // "homogeneous", or "grid NXxNYxNZ"
    uint64_t bytes = 0;
    float minDensity = 1, maxDensity = 1;
    Vec3f sigmaA, sigmaS;
    float g = 0;
  };
  std::vector<Medium> media;
  uint64_t mediumBoundaries = 0;
  uint64_t boundaryTriangles = 0;
  Box3f bounds;
  MemoryCost memory;

  uint64_t lights() const { return suns + pointLights + environments + emissiveMeshes; }
  nlohmann::json toJson() const;
  std::string toText() const;  // the human-readable table `ferry info` prints
};

SceneSummary summarize(const Scene& scene);
// The memory estimate of only the listed instances and what they reference:
// what one rank holds.
MemoryCost ownedMemory(const Scene& scene, const std::vector<int32_t>& instances);

// 1234567 -> "1.23 M"; bytes -> "1.18 MiB".
std::string formatCount(uint64_t n);
std::string formatBytes(uint64_t bytes);
// "2GiB", "1.5 GiB", "500MB", "64M", "4096": bytes (K/M/G/T and KiB.. are
// powers of 1024, KB.. powers of 1000). Throws InputError naming `what`.
uint64_t parseBytes(const std::string& text, const std::string& what);

}  // namespace ferry
