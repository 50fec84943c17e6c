// Heightfield terrain: a function y = height(x, z) meshed as a regular grid
// over a rectangle, with uvs spanning the rectangle once (for a generated
// image texture painted from the same function). Scatterers sample the
// function, not the mesh, so placement never needs the geometry.
#pragma once

#include <cmath>
#include <functional>
#include <limits>

#include "builtin/scene_plan.h"
#include "builtin/shapes.h"
#include "core/math.h"
#include "scene/scene.h"

namespace ferry::builtin {

using HeightFunction = std::function<float(float x, float z)>;

struct TerrainGrid {
  float x0 = -1, z0 = -1, x1 = 1, z1 = 1;
  int segments = 64;  // cells along each side
  // When finite, the boundary vertices sit at this height, so the terrain's
  // lowest point is known exactly without evaluating the function.
  float skirtY = std::numeric_limits<float>::quiet_NaN();

  // Vertex coordinates; the last one is exactly the far edge.
  float x(int i) const { return i >= segments ? x1 : x0 + (x1 - x0) * float(i) / float(segments); }
  float z(int j) const { return j >= segments ? z1 : z0 + (z1 - z0) * float(j) / float(segments); }
  // Nearest vertex coordinate, for features that must land on a vertex.
  float snapX(float x) const { return this->x(int(std::lround((x - x0) / (x1 - x0) * segments))); }
  float snapZ(float z) const { return this->z(int(std::lround((z - z0) / (z1 - z0) * segments))); }
  Vec2f uvAt(float x, float z) const { return {(x - x0) / (x1 - x0), (z - z0) / (z1 - z0)}; }
  Vec2f worldAt(Vec2f uv) const { return {x0 + uv.x * (x1 - x0), z0 + uv.y * (z1 - z0)}; }
  bool hasSkirt() const { return std::isfinite(skirtY); }
};

MeshCounts terrainCounts(const TerrainGrid& grid);
// Positions, normals (from the height grid) and uvs; rows in parallel.
Mesh buildTerrain(const TerrainGrid& grid, const HeightFunction& height);

// Tile (ti, tj) of `grid` cut into tiles x tiles pieces (its segments a
// multiple of `tiles`): the whole grid's vertices (exactly on the tile's
// edges, so neighbours meet without cracks; up to rounding inside). No
// skirt: the tile's edges are the function's.
TerrainGrid terrainTile(const TerrainGrid& grid, int tiles, int ti, int tj);

// A tile as a mesh of the plan (not yet an object): normals from the
// function, so neighbouring tiles agree at their seams, and uvs spanning the
// whole `grid`, so one texture painted over the grid covers every tile.
MeshRecipe terrainTileRecipe(std::string name, int32_t material, const TerrainGrid& grid,
                             const TerrainGrid& tile, HeightFunction height);

// Sets every normal of `m` from the function (heightNormal, step eps).
void heightNormals(Mesh& m, const HeightFunction& height, float eps);

// The side of a terrain's colour texture: the smallest power of two from 256
// to 8192 that is at least `texelsAcross`.
int terrainTextureSize(double texelsAcross);
// A size x size texture painted with colour(x, z) at the world point under
// each texel, mapped onto the terrain by its uvs (clamped at the edges).
int32_t addTerrainTexture(ScenePlan& plan, const std::string& name, const TerrainGrid& grid,
                          int size, std::function<Vec3f(float x, float z)> colour);

// Upward unit normal of the function by central differences.
Vec3f heightNormal(const HeightFunction& height, float x, float z, float eps);

}  // namespace ferry::builtin
