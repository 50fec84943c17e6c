#include "builtin/island_terrain.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "builtin/noise.h"
#include "core/error.h"

namespace ferry::builtin {
namespace {

// Cells [i0, i1] x [j0, j1] of a polar grid of rings x segments about an apex
// (ring 0); when i0 == 0 the cells touching the apex are a fan. Vertex (i, j)
// is at(i / rings, 2 pi (j mod segments) / segments) in every patch, so
// patches meet exactly.
MeshCounts polarPatchCounts(int i0, int i1, int j0, int j1) {
  uint64_t cols = uint64_t(j1 - j0);
  if (i0 == 0) return {1 + uint64_t(i1) * (cols + 1), cols + 2 * uint64_t(i1 - 1) * cols};
  return {uint64_t(i1 - i0 + 1) * (cols + 1), 2 * uint64_t(i1 - i0) * cols};
}

Mesh polarPatch(int rings, int segments, int i0, int i1, int j0, int j1,
                const std::function<Vec3f(float, float)>& at,
                const std::function<Vec2f(Vec3f)>& uvOf) {
  MeshBuilder b(true, true, polarPatchCounts(i0, i1, j0, j1));
  const int first = std::max(i0, 1), cols = j1 - j0;
  int32_t apex = -1;
  if (i0 == 0) {
    Vec3f p = at(0, 0);
    apex = b.vertex(p, {0, 1, 0}, uvOf(p));
  }
  const int32_t base = b.vertexCount();
  for (int i = first; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      float phi = 2 * kPi * float(j % segments) / float(segments);
      Vec3f p = at(float(i) / float(rings), phi);
      b.vertex(p, {0, 1, 0}, uvOf(p));
    }
  auto vertex = [&](int i, int j) { return base + (i - first) * (cols + 1) + (j - j0); };
  if (i0 == 0)
    for (int j = j0; j < j1; ++j) b.triangle(apex, vertex(1, j + 1), vertex(1, j));
  for (int i = first; i < i1; ++i)
    for (int j = j0; j < j1; ++j) {
      int32_t a = vertex(i, j), bb = vertex(i + 1, j), c = vertex(i + 1, j + 1),
              d = vertex(i, j + 1);
      b.triangle(a, d, c);
      b.triangle(a, c, bb);
    }
  return b.finish();
}

}  // namespace

std::string groundElement(const IslandShape& shape, Vec2f p) {
  IslandShape::Where w = shape.where(p.x, p.y);
  if (w.rho > 1.3f) return "osOcean";
  if (w.rho > 1.08f) return "isCoral";
  for (int k = 0; k < 2; ++k) {
    const Peak& peak = shape.peaks[size_t(k)];
    float dx = p.x - peak.centre.x, dz = p.y - peak.centre.y;
    if (dx * dx + dz * dz < 0.81f * peak.radius * peak.radius)
      return k == 0 ? "isMountainA" : "isMountainB";
  }
  if (w.rho > 0.8f) {
    if (IslandShape::beachIn(w) != kNoHeight) return "isBeach";
    if (shape.inCliff(p, 60)) return "isLavaRocks";
    return "isCoastline";
  }
  return p.x < 0 ? "isDunesA" : "isDunesB";
}

void addGroundTiles(ScenePlan& plan, const Shape& shape, const TerrainGrid& grid, int tiles,
                    int32_t material, ElementMeshes& out) {
  for (int tj = 0; tj < tiles; ++tj)
    for (int ti = 0; ti < tiles; ++ti) {
      TerrainGrid tile = terrainTile(grid, tiles, ti, tj);
      // Left out when every corner and the centre lie far out at sea, where
      // the ground is flat just above the seabed plane.
      float nearest = 1e9f;
      for (float x : {tile.x0, 0.5f * (tile.x0 + tile.x1), tile.x1})
        for (float z : {tile.z0, 0.5f * (tile.z0 + tile.z1), tile.z1})
          nearest = std::min(nearest, shape->where(x, z).rho);
      if (nearest > 1.5f) continue;
      Vec2f centre{0.5f * (tile.x0 + tile.x1), 0.5f * (tile.z0 + tile.z1)};
      std::string element = groundElement(*shape, centre);
      MeshRecipe r =
          terrainTileRecipe(fmt::format("{}/ground-{}-{}", element, ti, tj), material, grid, tile,
                            [shape](float x, float z) { return shape->ground(x, z); });
      out[element].push_back(plan.addMesh(std::move(r)));
    }
}

void addPeak(ScenePlan& plan, const Shape& shape, int k, const TerrainGrid& grid, int rings,
             int segments, int sectors, int32_t material, const std::string& element,
             ElementMeshes& out) {
  FERRY_CHECK_EQ(segments % sectors, 0);
  const int capRings = std::max(1, rings / 4);
  auto piece = [&](std::string name, int i0, int i1, int j0, int j1) {
    MeshRecipe r;
    r.name = std::move(name);
    r.material = material;  // painted by the ground texture, which knows the peaks
    r.counts = polarPatchCounts(i0, i1, j0, j1);
    r.build = [shape, grid, k, rings, segments, i0, i1, j0, j1] {
      const Peak& p = shape->peaks[size_t(k)];
      Mesh m = polarPatch(
          rings, segments, i0, i1, j0, j1,
          [&](float r, float phi) {
            float x = r == 0 ? p.centre.x : p.centre.x + r * p.radius * std::cos(phi);
            float z = r == 0 ? p.centre.y : p.centre.y + r * p.radius * std::sin(phi);
            return Vec3f(x, shape->peakAt(k, x, z, r), z);
          },
          [&](Vec3f q) { return grid.uvAt(q.x, q.z); });
      heightNormals(
          m,
          [&](float x, float z) {
            float dx = x - p.centre.x, dz = z - p.centre.y;
            return shape->peakAt(k, x, z, std::sqrt(dx * dx + dz * dz) / p.radius);
          },
          0.5f);
      return m;
    };
    out[element].push_back(plan.addMesh(std::move(r)));
  };
  piece(element + "/summit", 0, capRings, 0, segments);
  const int per = segments / sectors;
  for (int s = 0; s < sectors; ++s)
    piece(fmt::format("{}/slope-{}", element, s), capRings, rings, s * per, (s + 1) * per);
}

void addCliffs(ScenePlan& plan, const Shape& shape, int detail, int32_t material,
               ElementMeshes& out) {
  for (size_t k = 0; k < shape->cliffs.size(); ++k) {
    MeshRecipe r;
    r.name = fmt::format("isLavaRocks/cliff-{}", k);
    r.material = material;
    r.counts = cubeSphereCounts(detail);
    r.build = [shape, k, detail] {
      const Cliff& c = shape->cliffs[k];
      MeshBuilder b(true, true, cubeSphereCounts(detail));
      addCubeSphere(b, detail, [&](Vec3f dir) { return rockSurface(c.rock, c.seed, dir); });
      Mesh m = b.finish();
      // Into place: the cliff stands on the shore, its long side along it.
      Affine3f place =
          Affine3f::translate({c.centre.x, 0, c.centre.y}) * Affine3f::rotate({0, 1, 0}, c.yaw);
      for (size_t v = 0; v < m.positions.size(); ++v) {
        m.positions[v] = place.transformPoint(m.positions[v]);
        m.normals[v] = normalize(place.transformVector(m.normals[v]));
        m.uvs[v] = m.uvs[v] * 12.0f;
      }
      return m;
    };
    out["isLavaRocks"].push_back(plan.addMesh(std::move(r)));
  }
}

void addBeach(ScenePlan& plan, const Shape& shape, int nu, int nv, int pieces, int32_t material,
              ElementMeshes& out) {
  FERRY_CHECK_EQ(nu % pieces, 0);
  const int per = nu / pieces;
  const float arc = kCoastRadius * (kBeachTheta1 - kBeachTheta0);
  const float depth = kCoastRadius * (kBeachRho1 - kBeachRho0);
  for (int k = 0; k < pieces; ++k) {
    MeshRecipe r;
    r.name = fmt::format("isBeach/sand-{}", k);
    r.material = material;
    r.counts = gridCounts(per, nv);
    r.build = [shape, nu, nv, per, k, arc, depth] {
      MeshBuilder b(true, true, gridCounts(per, nv));
      addGrid(b, per, nv, [&](float u, float v) {
        // By the global column, so neighbouring pieces share their seam exactly.
        int column = k * per + int(std::lround(u * float(per)));
        float theta = kBeachTheta0 + (kBeachTheta1 - kBeachTheta0) * float(column) / float(nu);
        float rho = lerpf(kBeachRho0, kBeachRho1, v);
        Vec2f p = shape->polar(theta, rho);
        return Vec3f(p.x, IslandShape::beachAt(theta, rho), p.y);
      });
      Mesh m = b.finish();
      for (Vec2f& uv : m.uvs)
        uv = {(float(k) + uv.x) * arc / float(5 * nu / per), uv.y * depth / 5};
      computeVertexNormals(m);
      return m;
    };
    out["isBeach"].push_back(plan.addMesh(std::move(r)));
  }
}

void addReefMounds(ScenePlan& plan, const Shape& shape, int count, int detail, uint32_t seed,
                   int32_t material, ElementMeshes& out) {
  for (int k = 0; k < count; ++k) {
    HashRng rng(seed, 0x2eef, uint32_t(k));
    float theta = 2 * kPi * (float(k) + rng.uniform(0.2f, 0.8f)) / float(count);
    Vec2f at = shape->polar(theta, rng.uniform(1.14f, 1.22f));
    RockParams rock;
    rock.detail = detail;
    rock.radii = {rng.uniform(14, 22), 6, rng.uniform(10, 16)};
    rock.roughness = 0.3f;
    rock.sink = 0.5f;
    const uint32_t rockSeed = streamKey(seed, 0x2eee, uint32_t(k));
    const float yaw = rng.uniform(0, 2 * kPi);
    // Its top (at most radii.y (1 + roughness) above the base) stays 1 m
    // under the water.
    const float base = -1 - rock.radii.y * (1 + rock.roughness) * (1 - rock.sink) - 1;
    MeshRecipe r;
    r.name = fmt::format("isCoral/mound-{}", k);
    r.material = material;
    r.counts = cubeSphereCounts(detail);
    r.build = [rock, rockSeed, at, yaw, base, detail] {
      MeshBuilder b(true, true, cubeSphereCounts(detail));
      addCubeSphere(b, detail, [&](Vec3f dir) { return rockSurface(rock, rockSeed, dir); });
      Mesh m = b.finish();
      Affine3f place = Affine3f::translate({at.x, base, at.y}) * Affine3f::rotate({0, 1, 0}, yaw);
      for (size_t v = 0; v < m.positions.size(); ++v) {
        m.positions[v] = place.transformPoint(m.positions[v]);
        m.normals[v] = normalize(place.transformVector(m.normals[v]));
        m.uvs[v] = m.uvs[v] * 4.0f;
      }
      return m;
    };
    out["isCoral"].push_back(plan.addMesh(std::move(r)));
  }
}

void addSea(ScenePlan& plan, int32_t water, int32_t seabed, ElementMeshes& out) {
  auto square = [&](std::string name, int32_t material, float y, float x0, float z0, float x1,
                    float z1) {
    MeshRecipe r;
    r.name = std::move(name);
    r.material = material;
    r.counts = {4, 2};
    r.hasUvs = false;
    r.build = [=] {
      MeshBuilder b(true, false, {4, 2});
      int32_t a = b.vertex({x0, y, z0}), c = b.vertex({x0, y, z1}), d = b.vertex({x1, y, z1}),
              e = b.vertex({x1, y, z0});
      b.quad(a, c, d, e);
      return b.finish();
    };
    out["osOcean"].push_back(plan.addMesh(std::move(r)));
  };
  const float w = kOceanHalfSize;
  for (int q = 0; q < 4; ++q) {
    float x0 = q % 2 == 0 ? -w : 0, z0 = q / 2 == 0 ? -w : 0;
    square(fmt::format("osOcean/water-{}", q), water, 0, x0, z0, x0 + w, z0 + w);
  }
  // Beyond the ground tiles, out to the ocean's edge: without it the sea
  // would look different over the ground than beyond it.
  square("osOcean/seabed", seabed, kSeabed, -w, -w, w, w);
}

}  // namespace ferry::builtin
