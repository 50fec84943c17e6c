#include "builtin/terrain.h"

#include <vector>

#include <tbb/parallel_for.h>

#include "builtin/procedural_texture.h"
#include "core/error.h"

namespace ferry::builtin {

MeshCounts terrainCounts(const TerrainGrid& grid) {
  return gridCounts(grid.segments, grid.segments);
}

Mesh buildTerrain(const TerrainGrid& grid, const HeightFunction& height) {
  FERRY_CHECK_GE(grid.segments, 1);
  const int n = grid.segments;
  const int stride = n + 1;
  const size_t vertexCount = size_t(stride) * size_t(stride);
  Mesh mesh;
  mesh.positions.resize(vertexCount);
  mesh.normals.resize(vertexCount);
  mesh.uvs.resize(vertexCount);
  mesh.indices.resize(2 * size_t(n) * size_t(n));

  tbb::parallel_for(0, stride, [&](int j) {
    const float z = grid.z(j);
    for (int i = 0; i < stride; ++i) {
      const float x = grid.x(i);
      bool boundary = i == 0 || j == 0 || i == n || j == n;
      float y = boundary && grid.hasSkirt() ? grid.skirtY : height(x, z);
      size_t v = size_t(j) * stride + i;
      mesh.positions[v] = {x, y, z};
      mesh.uvs[v] = grid.uvAt(x, z);
    }
  });
  tbb::parallel_for(0, stride, [&](int j) {
    for (int i = 0; i < stride; ++i) {
      auto at = [&](int ii, int jj) {
        return mesh.positions[size_t(std::clamp(jj, 0, n)) * stride + std::clamp(ii, 0, n)];
      };
      Vec3f dx = at(i + 1, j) - at(i - 1, j);
      Vec3f dz = at(i, j + 1) - at(i, j - 1);
      Vec3f normal = cross(dz, dx);  // +y for a flat grid: z x x = y
      float len = length(normal);
      mesh.normals[size_t(j) * stride + i] = len > 0 ? normal / len : Vec3f(0, 1, 0);
    }
  });
  tbb::parallel_for(0, n, [&](int j) {
    for (int i = 0; i < n; ++i) {
      int32_t v00 = j * stride + i, v01 = v00 + stride;
      size_t t = 2 * (size_t(j) * n + i);
      // Counter-clockwise seen from above, so the geometric normal is +y.
      mesh.indices[t] = {v00, v01, v01 + 1};
      mesh.indices[t + 1] = {v00, v01 + 1, v00 + 1};
    }
  });
  return mesh;
}

TerrainGrid terrainTile(const TerrainGrid& grid, int tiles, int ti, int tj) {
  FERRY_CHECK_GE(tiles, 1);
  FERRY_CHECK_EQ(grid.segments % tiles, 0);
  const int cells = grid.segments / tiles;
  TerrainGrid tile;
  tile.x0 = grid.x(ti * cells);
  tile.x1 = grid.x((ti + 1) * cells);
  tile.z0 = grid.z(tj * cells);
  tile.z1 = grid.z((tj + 1) * cells);
  tile.segments = cells;
  return tile;
}

MeshRecipe terrainTileRecipe(std::string name, int32_t material, const TerrainGrid& grid,
                             const TerrainGrid& tile, HeightFunction height) {
  MeshRecipe r;
  r.name = std::move(name);
  r.material = material;
  r.counts = terrainCounts(tile);
  const float eps = 0.5f * (grid.x1 - grid.x0) / float(grid.segments);
  r.build = [tile, grid, eps, height = std::move(height)] {
    Mesh m = buildTerrain(tile, height);
    heightNormals(m, height, eps);
    for (Vec2f& uv : m.uvs)
      uv = grid.uvAt(tile.x0 + uv.x * (tile.x1 - tile.x0), tile.z0 + uv.y * (tile.z1 - tile.z0));
    return m;
  };
  return r;
}

void heightNormals(Mesh& m, const HeightFunction& height, float eps) {
  tbb::parallel_for(size_t(0), m.positions.size(), [&](size_t v) {
    m.normals[v] = heightNormal(height, m.positions[v].x, m.positions[v].z, eps);
  });
}

int terrainTextureSize(double texelsAcross) {
  int size = 256;
  while (size < 8192 && size < texelsAcross) size *= 2;
  return size;
}

int32_t addTerrainTexture(ScenePlan& plan, const std::string& name, const TerrainGrid& grid,
                          int size, std::function<Vec3f(float x, float z)> colour) {
  return plan.addTexture({name, size, size, [name, grid, size, colour] {
                            return paintTexture(name, size, size, WrapMode::Clamp, [&](Vec2f uv) {
                              Vec2f p = grid.worldAt(uv);
                              Vec3f c = colour(p.x, p.y);
                              return Vec4f{c.x, c.y, c.z, 1};
                            });
                          }});
}

Vec3f heightNormal(const HeightFunction& height, float x, float z, float eps) {
  float dhdx = (height(x + eps, z) - height(x - eps, z)) / (2 * eps);
  float dhdz = (height(x, z + eps) - height(x, z - eps)) / (2 * eps);
  return normalize(Vec3f(-dhdx, 1, -dhdz));
}

}  // namespace ferry::builtin
