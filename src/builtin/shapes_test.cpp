// Every primitive and plant generator makes exactly the counts it promises:
// the built-ins' descriptions rest on it.
#include "builtin/shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "builtin/noise.h"
#include "builtin/plants.h"
#include "builtin/procedural_texture.h"
#include "builtin/terrain.h"

namespace ferry::builtin {
namespace {

MeshCounts countsOf(const Mesh& m) {
  return {m.vertexCount(), m.triangleCount()};
}

void expectWellFormed(const Mesh& m) {
  for (const Vec3i& t : m.indices)
    for (int k = 0; k < 3; ++k) {
      ASSERT_GE(t[k], 0);
      ASSERT_LT(uint64_t(t[k]), m.vertexCount());
    }
  for (const Vec3f& p : m.positions) ASSERT_TRUE(isFinite(p));
  if (!m.normals.empty()) {
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (const Vec3f& n : m.normals) ASSERT_NEAR(length(n), 1.0f, 1e-3f);
  }
  if (!m.uvs.empty()) {
    ASSERT_EQ(m.uvs.size(), m.positions.size());
  }
}

TEST(BuiltinShapes, PrimitivesMakeTheirCounts) {
  for (int n : {1, 2, 5, 16}) {
    MeshBuilder b(true, true, {});
    std::vector<Vec3f> c(n + 1);
    std::vector<float> r(n + 1, 0.1f);
    std::vector<Vec3f> s(n + 1, Vec3f(1, 0, 0));
    for (int i = 0; i <= n; ++i) c[i] = {0, float(i), 0.1f * float(i * i)};
    addTube(b, c, r, 3 + n);
    EXPECT_EQ(countsOf(b.mesh()), tubeCounts(n + 1, 3 + n));
    MeshBuilder rb(true, true, {});
    addRibbon(rb, c, s, r);
    EXPECT_EQ(countsOf(rb.mesh()), ribbonCounts(n));
    MeshBuilder cb(true, true, {});
    addCubeSphere(cb, n, [](Vec3f d) { return d * 2.0f; });
    EXPECT_EQ(countsOf(cb.mesh()), cubeSphereCounts(n));
    MeshBuilder gb(true, true, {});
    addGrid(gb, n, n + 1, [](float u, float v) { return Vec3f(u, 0, v); });
    EXPECT_EQ(countsOf(gb.mesh()), gridCounts(n, n + 1));
    MeshBuilder pb(true, true, {});
    addPolarCap(
        pb, n, 3 + n,
        [](float r, float phi) { return Vec3f(r * std::cos(phi), 1 - r, r * std::sin(phi)); },
        [](Vec3f p) {
          return Vec2f{p.x, p.z};
        });
    EXPECT_EQ(countsOf(pb.mesh()), polarCapCounts(n, 3 + n));
    MeshBuilder ub(true, true, {});
    addUvSphere(ub, 2 + n, 3 + n, {0, 0, 0}, 1);
    EXPECT_EQ(countsOf(ub.mesh()), uvSphereCounts(2 + n, 3 + n));
    for (MeshBuilder* m : {&b, &rb, &cb, &gb, &pb, &ub}) expectWellFormed(m->mesh());
  }
}

TEST(BuiltinShapes, CubeSphereWindsOutwards) {
  MeshBuilder b(true, true, {});
  addCubeSphere(b, 6, [](Vec3f d) { return d; });
  const Mesh& m = b.mesh();
  for (const Vec3i& t : m.indices) {
    Vec3f p0 = m.positions[t.x], p1 = m.positions[t.y], p2 = m.positions[t.z];
    EXPECT_GT(dot(cross(p1 - p0, p2 - p0), p0 + p1 + p2), 0);
  }
  for (size_t v = 0; v < m.positions.size(); ++v)
    EXPECT_GT(dot(m.normals[v], m.positions[v]), 0.99f);
}

TEST(BuiltinShapes, TerrainMeshFollowsTheFunctionAndFacesUp) {
  TerrainGrid grid;
  grid.x0 = -10, grid.x1 = 10, grid.z0 = -5, grid.z1 = 15;
  grid.segments = 20;
  auto height = [](float x, float z) { return 0.1f * x + 0.05f * z * z / 10; };
  Mesh m = buildTerrain(grid, height);
  EXPECT_EQ(countsOf(m), terrainCounts(grid));
  expectWellFormed(m);
  for (const Vec3f& p : m.positions) EXPECT_FLOAT_EQ(p.y, height(p.x, p.z));
  for (const Vec3i& t : m.indices) {
    Vec3f n = cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]);
    EXPECT_GT(n.y, 0);
  }
  EXPECT_EQ(m.bounds().lower.x, -10);
  EXPECT_EQ(m.bounds().upper.z, 15);
  grid.skirtY = -3;
  Mesh skirted = buildTerrain(grid, height);
  EXPECT_EQ(skirted.bounds().lower.y, -3);
}

void expectDesignMakesItsCounts(const PlantDesign& design) {
  ASSERT_FALSE(design.empty());
  for (const PlantPart& part : design) {
    Mesh m = part.build();
    SCOPED_TRACE(part.name);
    EXPECT_EQ(countsOf(m), part.counts);
    EXPECT_EQ(!m.normals.empty(), part.hasNormals);
    EXPECT_EQ(!m.uvs.empty(), part.hasUvs);
    expectWellFormed(m);
  }
}

TEST(BuiltinPlants, EveryGeneratorMakesItsCounts) {
  for (uint32_t seed : {1u, 2u, 99u}) {
    TreeParams tree;
    tree.levels = {{5, 6, 5, 0.6f, 0.5f, 50, 0.4f, 0.2f, 0.4f},
                   {3, 4, 4, 0.5f, 0.5f, 40, 0.3f, 0.1f, 0.4f}};
    tree.aerialRoots = int(seed % 5);
    expectDesignMakesItsCounts(designTree(tree, seed));
    tree.levels.clear();
    expectDesignMakesItsCounts(designTree(tree, seed));
    PalmParams palm;
    palm.coconuts = int(seed % 3);
    expectDesignMakesItsCounts(designPalm(palm, seed));
    expectDesignMakesItsCounts(designFern({}, seed));
    expectDesignMakesItsCounts(designGrass({}, seed));
    FlowerParams flowers;
    flowers.leavesPerStem = int(seed % 3);
    expectDesignMakesItsCounts(designFlowers(flowers, seed));
    expectDesignMakesItsCounts(designRock({}, seed));
    expectDesignMakesItsCounts(designLog({}, seed));
  }
}

// The triangles of a design, as sorted vertex triples (to compare designs
// cut into meshes differently).
std::vector<std::array<float, 9>> trianglesOf(const PlantDesign& design, PartRole role) {
  std::vector<std::array<float, 9>> out;
  for (const PlantPart& part : design) {
    if (part.role != role) continue;
    Mesh m = part.build();
    for (const Vec3i& t : m.indices) {
      std::array<float, 9> tri;
      for (int k = 0; k < 3; ++k) {
        const Vec3f& p = m.positions[size_t(t[k])];
        tri[size_t(3 * k)] = p.x, tri[size_t(3 * k + 1)] = p.y, tri[size_t(3 * k + 2)] = p.z;
      }
      out.push_back(tri);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Production plant models come as a mesh per branch level and several leaf
// meshes (the landscape's trees): the cut changes the meshes, not the tree.
TEST(BuiltinPlants, TreesCutIntoMeshesAreTheSameTree) {
  TreeParams whole;
  whole.levels = {{5, 6, 5, 0.6f, 0.5f, 50, 0.4f, 0.2f, 0.4f},
                  {3, 4, 4, 0.5f, 0.5f, 40, 0.3f, 0.1f, 0.4f}};
  whole.aerialRoots = 3;
  TreeParams cut = whole;
  cut.woodByLevel = true;
  cut.leafMeshes = 4;
  PlantDesign one = designTree(whole, 7), many = designTree(cut, 7);
  ASSERT_EQ(one.size(), 2u);
  ASSERT_EQ(many.size(), 3u + 4u);  // trunk, two branch levels, four leaf runs
  expectDesignMakesItsCounts(many);
  EXPECT_EQ(designCounts(one), designCounts(many));
  EXPECT_EQ(trianglesOf(one, PartRole::Wood), trianglesOf(many, PartRole::Wood));
  EXPECT_EQ(trianglesOf(one, PartRole::Leaves), trianglesOf(many, PartRole::Leaves));
  for (int g = 0; g < 4; ++g) EXPECT_EQ(many[size_t(3 + g)].group, g);
  // More leaf meshes than tips: one per tip.
  cut.leafMeshes = 1000;
  EXPECT_EQ(designTree(cut, 7).size(), 3u + 15u);
}

TEST(BuiltinPlants, PatchesAreTheirClumpsInGroups) {
  PatchParams p;
  p.radius = 2;
  p.clumps = 10;
  p.groups = 3;
  auto clump = [](int k) {
    FlowerParams f;
    f.stems = 2 + k % 3;
    return designFlowers(f, uint32_t(k));
  };
  PlantDesign patch = designPatch(p, clump, 5);
  const size_t parts = clump(0).size();
  ASSERT_EQ(patch.size(), 3 * parts);
  expectDesignMakesItsCounts(patch);
  MeshCounts total;
  for (int k = 0; k < p.clumps; ++k) total += designCounts(clump(k));
  EXPECT_EQ(designCounts(patch), total);
  for (size_t i = 0; i < patch.size(); ++i) {
    EXPECT_EQ(patch[i].group, int(i / parts));
    EXPECT_EQ(patch[i].role, clump(0)[i % parts].role);
  }
  // Every clump stands in the disc (its own spread and petals aside).
  for (const PlantPart& part : patch) {
    Box3f b = part.build().bounds();
    EXPECT_LT(std::max({std::abs(b.lower.x), std::abs(b.upper.x), std::abs(b.lower.z),
                        std::abs(b.upper.z)}),
              p.radius + 1);
  }
}

TEST(BuiltinShapes, TerrainTilesMeetTheWholeGrid) {
  TerrainGrid grid;
  grid.x0 = -10, grid.x1 = 30, grid.z0 = 0, grid.z1 = 20;
  grid.segments = 12;
  HeightFunction height = [](float x, float z) { return std::sin(0.3f * x) + 0.1f * z; };
  Mesh whole = buildTerrain(grid, height);
  size_t triangles = 0;
  std::map<std::array<float, 3>, int> tilesAt;  // exact position -> tiles with a vertex there
  std::vector<Vec3f> edgeVertices;
  for (int tj = 0; tj < 3; ++tj)
    for (int ti = 0; ti < 3; ++ti) {
      const TerrainGrid tile = terrainTile(grid, 3, ti, tj);
      MeshRecipe r = terrainTileRecipe("t", 0, grid, tile, height);
      Mesh m = r.build();
      EXPECT_EQ(countsOf(m), r.counts);
      expectWellFormed(m);
      triangles += m.triangleCount();
      for (size_t v = 0; v < m.positions.size(); ++v) {
        const Vec3f& p = m.positions[v];
        ++tilesAt[{p.x, p.y, p.z}];
        // A vertex of the whole grid (up to rounding), with its uv.
        size_t nearest = 0;
        for (size_t w = 1; w < whole.positions.size(); ++w)
          if (length(whole.positions[w] - p) < length(whole.positions[nearest] - p)) nearest = w;
        EXPECT_LT(length(whole.positions[nearest] - p), 1e-4f) << v;
        EXPECT_NEAR(whole.uvs[nearest].x, m.uvs[v].x, 1e-6f);
        EXPECT_NEAR(whole.uvs[nearest].y, m.uvs[v].y, 1e-6f);
        const bool onTileEdge =
            p.x == tile.x0 || p.x == tile.x1 || p.z == tile.z0 || p.z == tile.z1;
        const bool onGridEdge =
            p.x == grid.x0 || p.x == grid.x1 || p.z == grid.z0 || p.z == grid.z1;
        if (onTileEdge && !onGridEdge) edgeVertices.push_back(p);
      }
    }
  EXPECT_EQ(triangles, whole.triangleCount());
  // Where tiles meet, each edge vertex is exactly a neighbour's: no cracks.
  for (const Vec3f& p : edgeVertices) EXPECT_GE((tilesAt[{p.x, p.y, p.z}]), 2) << p.x << " " << p.z;
}

TEST(BuiltinPlants, RocksStayWithinTheirStatedBound) {
  RockParams p;
  p.radii = {3, 2, 1};
  p.roughness = 0.25f;
  p.sink = 0.5f;
  Mesh m = designRock(p, 5)[0].build();
  Vec3f centre{0, p.radii.y * (1 - p.sink), 0};
  for (const Vec3f& v : m.positions) {
    Vec3f d = (v - centre) / p.radii;
    EXPECT_LE(length(d), 1 + p.roughness + 1e-4f);
    EXPECT_GE(length(d), 1 - p.roughness - 1e-4f);
  }
}

TEST(BuiltinPlants, TreesStandOnTheOrigin) {
  TreeParams tree;
  tree.levels = {{5, 6, 5, 0.6f, 0.5f, 50, 0.4f, 0.2f, 0.4f}};
  Mesh wood = designTree(tree, 3)[0].build();
  Box3f b = wood.bounds();
  EXPECT_LT(b.lower.y, 0.0f);
  EXPECT_GT(b.lower.y, -0.5f);
  EXPECT_GT(b.upper.y, tree.trunkLength * 0.9f);
  EXPECT_LT(std::abs(b.center().x), tree.trunkLength);
}

TEST(BuiltinTextures, CardsHaveHolesAndSolidParts) {
  Texture leaf = leafClusterTexture("leaf", 64, 1, {0.2f, 0.4f, 0.1f}, {0.05f, 0.1f, 0.02f}, 9);
  Texture frond =
      frondTexture("frond", 64, 128, 1, {0.2f, 0.4f, 0.1f}, {0.05f, 0.1f, 0.02f}, 30, 0.45f);
  Texture needles = needleTexture("needles", 64, 1, {0.2f, 0.4f, 0.1f}, {0.05f, 0.1f, 0.02f});
  Texture petal = petalTexture("petal", 64, {1, 0.8f, 0.2f});
  for (const Texture* t : {&leaf, &frond, &needles, &petal}) {
    ASSERT_EQ(t->rgba.size(), t->texelCount() * 4);
    size_t holes = 0;
    for (size_t i = 3; i < t->rgba.size(); i += 4) holes += t->rgba[i] == 0;
    EXPECT_GT(holes, t->texelCount() / 20) << t->name;
    EXPECT_LT(holes, t->texelCount() * 19 / 20) << t->name;
    EXPECT_TRUE(t->srgb);
  }
  Texture bark = barkTexture("bark", 32, 32, 1, Vec3f(0.1f), Vec3f(0.5f), BarkStyle::Furrowed);
  for (size_t i = 3; i < bark.rgba.size(); i += 4) EXPECT_EQ(bark.rgba[i], 255);
}

TEST(BuiltinTextures, TileableNoiseWraps) {
  for (float v : {0.1f, 0.5f, 0.77f}) {
    EXPECT_NEAR(tileableFbm({0.0f, v}, 5, 3, 4), tileableFbm({1.0f, v}, 5, 3, 4), 1e-5f);
    EXPECT_NEAR(tileableFbm({v, 0.0f}, 5, 3, 4), tileableFbm({v, 1.0f}, 5, 3, 4), 1e-5f);
  }
}

TEST(BuiltinNoise, StreamsAreDeterministicAndIndependent) {
  HashRng a(7, 1, 2), b(7, 1, 2), c(7, 1, 3), d(8, 1, 2);
  int sameC = 0, sameD = 0;
  for (int i = 0; i < 100; ++i) {
    float x = a.uniform();
    EXPECT_EQ(x, b.uniform());
    EXPECT_GE(x, 0.0f);
    EXPECT_LT(x, 1.0f);
    sameC += x == c.uniform();
    sameD += x == d.uniform();
  }
  EXPECT_LT(sameC, 3);
  EXPECT_LT(sameD, 3);
  float lo = 1, hi = -1;
  for (int i = 0; i < 10000; ++i) {
    float n = fbm(float(i) * 0.37f, float(i) * 0.11f, 5, 4);
    lo = std::min(lo, n), hi = std::max(hi, n);
  }
  EXPECT_GT(lo, -1.2f);
  EXPECT_LT(hi, 1.2f);
  EXPECT_LT(lo, -0.3f);
  EXPECT_GT(hi, 0.3f);
}

}  // namespace
}  // namespace ferry::builtin
