// A built-in scene as a recipe: every mesh with its exact counts and a
// function that makes it, every object, every batch of instances with a
// function that places instance i, every texture with its size and a function
// that paints it. Describing a plan only adds up numbers, so `ferry info` on
// a scene of 1e10 instanced triangles is instant; materializing runs all the
// functions (in parallel, each a pure function of the plan) and yields a
// Scene whose summary equals the description.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "builtin/shapes.h"
#include "scene/mesh_store.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry::builtin {

struct MeshRecipe {
  std::string name;
  int32_t material = 0;
  MeshCounts counts;
  bool hasNormals = true;
  bool hasUvs = true;
  // Makes positions, normals, uvs and indices; the name and material are set
  // from the recipe. Must produce exactly `counts`.
  std::function<Mesh()> build;
};

struct TextureRecipe {
  std::string name;
  int width = 0;
  int height = 0;
  std::function<Texture()> build;  // must produce width x height texels
};

struct ObjectRecipe {
  std::string name;
  std::vector<int32_t> meshes;
};

// A geometry of another kind than a triangle mesh (scene/shape.h), its own
// object placed once with the identity transform. `build` must make a shape
// of exactly `primitives` primitives and `bytes` bytes (Shape::bytes()).
struct ShapeRecipe {
  std::string name;
  std::string kind;  // Shape::kind() of what build makes
  int32_t material = 0;
  uint64_t primitives = 0;
  uint32_t piecesPerPrimitive = 1;  // Shape::piecesPerPrimitive() of what build makes
  uint64_t bytes = 0;
  double accelBytesPerBox = MemoryModel::kAccelBytesPerShapeBox;  // see geometryCost
  std::function<std::shared_ptr<const Shape>()> build;
};

// `count` instances of one object; `transform(i)` places instance i and must
// be a pure function of i, so instances can be made in any order or in parallel.
struct InstanceBatch {
  int32_t object = 0;
  uint64_t count = 0;
  std::function<Affine3f(uint64_t)> transform;
};

struct ScenePlan {
  std::string name;
  std::vector<Material> materials;
  std::vector<TextureRecipe> textures;
  std::vector<MeshRecipe> meshes;
  std::vector<ObjectRecipe> objects;
  std::vector<InstanceBatch> batches;
  std::vector<ShapeRecipe> shapes;  // after the objects and instances above
  std::vector<SunLight> suns;
  Vec3f environmentColor{0, 0, 0};
  std::function<std::shared_ptr<const HdrImage>()> environmentImage;  // optional
  std::vector<CameraView> views;
  // Participating media: what `ferry info` says of them without making them,
  // and what makes them and their boundaries into the scene (optional).
  std::vector<SceneSummary::Medium> mediaSummary;
  uint64_t mediumBoundaries = 0, boundaryTriangles = 0;
  uint64_t boundaryBytes = 0;  // the boundary meshes' MemoryCost (with their BVH)
  std::function<void(Scene&)> makeMedia;
  // The world bounds of everything the plan makes. Each generator guarantees
  // by construction that its content spans exactly this box (some vertex
  // touches each face), without making the content to find out.
  Box3f bounds;

  int32_t addMaterial(Material m);
  int32_t addTexture(TextureRecipe t);
  int32_t addMesh(MeshRecipe m);
  int32_t addObject(std::string objectName, std::vector<int32_t> meshIndices);
  void addInstances(int32_t object, uint64_t count, std::function<Affine3f(uint64_t)> transform);
  // A mesh that is its own object, placed once with the identity transform.
  int32_t addSingleInstanceMesh(MeshRecipe m);

  MeshCounts objectCounts(int32_t object) const;
  uint64_t instanceCount() const;
};

// A Lambertian material, its colour multiplied by `texture` when one is
// given, and cut out where the texture's alpha is low if `alphaCutout`.
int32_t addDiffuseMaterial(ScenePlan& plan, const std::string& name, Vec3f colour,
                           int32_t texture = kNoTexture, bool alphaCutout = false);

// A studio: a square floor at height `floorY`, `extent` out from the
// vertical axis each way, and a backdrop rising from its far edge (z =
// -extent) to `top`; the plan's bounds grow to span it.
void addStudio(ScenePlan& plan, int32_t material, float extent, float floorY, float top);

// Daylight: a sun of the real sun's size and clear-day irradiance towards
// `towardsSun` (any length), and a sky of unit scale fading from `zenith` to
// `horizon`, and to `below` over `belowFade` radians under the horizon.
void addDaylight(ScenePlan& plan, Vec3f towardsSun, Vec3f zenith, Vec3f horizon, Vec3f below,
                 float belowFade);

// The daylight and front view of a subject within about 1.2 of the origin
// in a studio (builtin:particles, builtin:tets).
void addStudioDaylightAndView(ScenePlan& plan);

SceneSummary describePlan(const ScenePlan& plan);
// Throws InternalError if a recipe makes something other than it promised.
// With `store`, each mesh goes to it as soon as it is made (Mesh::stored):
// the meshes are never all in memory (ferry partition --memory-budget).
Scene materializePlan(const ScenePlan& plan, std::shared_ptr<MeshStore> store = nullptr);

}  // namespace ferry::builtin
