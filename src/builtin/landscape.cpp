#include "builtin/landscape.h"

#include <array>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "builtin/noise.h"
#include "builtin/plants.h"
#include "builtin/procedural_texture.h"
#include "builtin/terrain.h"
#include "builtin/vegetation.h"

namespace ferry::builtin {
namespace {

// Layout, in metres. The terrain's edges (at height 0) and the knoll's
// summit vertex are the scene's bounds; plants are kept strictly inside.
constexpr float kHalfSize = 160;
constexpr float kBorder = 30;  // the ground falls to 0 over this strip at the edges
constexpr float kHillHeight = 14;
constexpr float kKnollHeight = 48;  // summit: the scene's highest point
constexpr float kKnollRadius = 80;
constexpr float kVegetationLine =
    18;  // tallest plant (scaled) < 30 m, so all stay below the summit
constexpr float kLowestGround = 2.5f;  // plants sunk or tilted into the ground stay above 0
constexpr float kEdgeMargin = 20;      // widest crown (scaled) < 20 m
constexpr float kPathHalfWidth = 1.3f;

uint64_t scaledCount(double base, double scale) {
  double n = std::round(base * scale);
  return uint64_t(std::clamp(n, 1.0, 9.0e15));
}

class LandscapeShape {
 public:
  LandscapeShape(uint32_t seed, const TerrainGrid& grid) : seed_(seed) {
    // On a vertex, so the mesh reaches the summit height exactly.
    knoll = {grid.snapX(-50), grid.snapZ(-85)};
  }

  // Where the "view-3" camera stands; trees and shrubs keep clear of it.
  static constexpr Vec2f kLookout{128, 118};
  static constexpr float kLookoutClearing = 22;
  static bool nearLookout(Vec2f p) {
    float dx = p.x - kLookout.x, dz = p.y - kLookout.y;
    return dx * dx + dz * dz < kLookoutClearing * kLookoutClearing;
  }

  float hills(float x, float z) const {
    float h = kHillHeight * (0.5f + 0.6f * fbm(x / 110, z / 110, seed_ + 1, 5)) +
              0.6f * fbm(x / 12, z / 12, seed_ + 2, 2);
    return std::clamp(h, 0.0f, kHillHeight);
  }
  float knollAt(float x, float z) const {
    float dx = x - knoll.x, dz = z - knoll.y;
    float d = std::sqrt(dx * dx + dz * dz) / kKnollRadius;
    if (d >= 1) return 0;
    float ridge = 1 - std::abs(fbm(x / 40, z / 40, seed_ + 3, 3));
    return kKnollHeight * std::pow(1 - d, 1.6f) * (1 - 0.3f * d * ridge);
  }
  static float edgeFade(float x, float z) {
    return smoothstep(0, kBorder, kHalfSize - std::abs(x)) *
           smoothstep(0, kBorder, kHalfSize - std::abs(z));
  }
  float height(float x, float z) const {
    return edgeFade(x, z) * std::max(hills(x, z), knollAt(x, z));
  }

  static float pathZ(float x) { return -10 + 20 * std::sin(x / 50 + 0.5f) + 8 * std::sin(x / 23); }
  static float pathDistance(float x, float z) {
    float slope = 20.0f / 50 * std::cos(x / 50 + 0.5f) + 8.0f / 23 * std::cos(x / 23);
    return std::abs(z - pathZ(x)) / std::sqrt(1 + slope * slope);
  }
  // > 0 in woods, < 0 in meadows.
  float forest(float x, float z) const { return fbm(x / 70, z / 70, seed_ + 5, 3); }

  Vec2f knoll;

 private:
  uint32_t seed_;
};

using Shape = std::shared_ptr<const LandscapeShape>;

// Ground cover (grass, ferns, flowers) may grow by the lookout; taller plants may not.
Ground landscapeGround(const Shape& shape, bool groundCover, float pathClearance, float forestMin,
                       float forestMax, float yMax = kVegetationLine) {
  Ground g;
  g.sample = [](HashRng& rng) {
    float w = kHalfSize - kEdgeMargin;
    return Vec2f{rng.uniform(-w, w), rng.uniform(-w, w)};
  };
  g.accept = [shape, groundCover, pathClearance, forestMin, forestMax, yMax](Vec2f p, float& y) {
    float w = kHalfSize - kEdgeMargin;
    if (std::abs(p.x) > w || std::abs(p.y) > w) return false;
    if (!groundCover && LandscapeShape::nearLookout(p)) return false;
    if (LandscapeShape::pathDistance(p.x, p.y) < pathClearance) return false;
    float f = shape->forest(p.x, p.y);
    if (f < forestMin || f > forestMax) return false;
    y = shape->height(p.x, p.y);
    return y >= kLowestGround && y <= yMax;
  };
  g.normal = [shape](Vec2f p) {
    return heightNormal([&](float x, float z) { return shape->height(x, z); }, p.x, p.y, 0.5f);
  };
  return g;
}

Vec3f groundColour(const LandscapeShape& shape, float x, float z, uint32_t seed) {
  const Vec3f meadow{0.16f, 0.27f, 0.06f}, dryGrass{0.3f, 0.28f, 0.1f}, woods{0.1f, 0.09f, 0.04f};
  const Vec3f dirt{0.26f, 0.19f, 0.11f}, stone{0.25f, 0.24f, 0.22f};
  float n = fbm(x / 6, z / 6, seed + 61, 3);
  float coarse = fbm(x / 40, z / 40, seed + 63, 2);
  Vec3f c = lerp(meadow, dryGrass, std::clamp(0.4f + 0.8f * coarse, 0.0f, 1.0f));
  c = lerp(c, woods, smoothstep(-0.05f, 0.25f, shape.forest(x, z)));
  c = lerp(c, stone, smoothstep(24, 36, shape.height(x, z) + 4 * n));
  float path = 1 - smoothstep(kPathHalfWidth - 0.3f, kPathHalfWidth + 0.3f,
                              LandscapeShape::pathDistance(x, z) + 0.4f * n);
  c = lerp(c, dirt, path);
  return c * (0.85f + 0.15f * n);
}

}  // namespace

ScenePlan planLandscape(double scale, uint32_t seed) {
  ScenePlan plan;
  plan.name = "landscape";

  TerrainGrid grid;
  grid.x0 = grid.z0 = -kHalfSize;
  grid.x1 = grid.z1 = kHalfSize;
  grid.segments = int(std::clamp(std::round(512 * std::sqrt(scale)), 64.0, 16384.0));
  grid.skirtY = 0;
  auto shape = std::make_shared<const LandscapeShape>(seed, grid);

  // ------------------------------------------------------------ textures
  int terrainTexels = 256;
  while (terrainTexels < 8192 && terrainTexels < 1024 * std::sqrt(scale) * 0.75) terrainTexels *= 2;
  auto texture = [&](std::string name, int w, int h, std::function<Texture()> build) {
    return plan.addTexture({std::move(name), w, h, std::move(build)});
  };
  int32_t terrainTex = texture("landscape-terrain", terrainTexels, terrainTexels, [=] {
    return paintTexture("landscape-terrain", terrainTexels, terrainTexels, WrapMode::Clamp,
                        [&](Vec2f uv) {
                          Vec2f p = grid.worldAt(uv);
                          Vec3f c = groundColour(*shape, p.x, p.y, seed);
                          return Vec4f{c.x, c.y, c.z, 1};
                        });
  });
  int32_t oakBarkTex = texture("oak-bark", 256, 256, [=] {
    return barkTexture("oak-bark", 256, 256, seed + 1, {0.05f, 0.04f, 0.03f}, {0.22f, 0.18f, 0.13f},
                       BarkStyle::Furrowed);
  });
  int32_t birchBarkTex = texture("birch-bark", 256, 256, [=] {
    return barkTexture("birch-bark", 256, 256, seed + 2, {0.04f, 0.035f, 0.03f},
                       {0.75f, 0.73f, 0.68f}, BarkStyle::Birch);
  });
  int32_t pineBarkTex = texture("pine-bark", 256, 256, [=] {
    return barkTexture("pine-bark", 256, 256, seed + 3, {0.07f, 0.035f, 0.02f},
                       {0.3f, 0.16f, 0.09f}, BarkStyle::Furrowed);
  });
  int32_t oakLeafTex = texture("oak-leaves", 256, 256, [=] {
    return leafClusterTexture("oak-leaves", 256, seed + 4, {0.2f, 0.36f, 0.07f},
                              {0.04f, 0.12f, 0.02f}, 9);
  });
  int32_t autumnLeafTex = texture("autumn-leaves", 256, 256, [=] {
    return leafClusterTexture("autumn-leaves", 256, seed + 5, {0.75f, 0.35f, 0.05f},
                              {0.35f, 0.08f, 0.02f}, 9);
  });
  int32_t birchLeafTex = texture("birch-leaves", 256, 256, [=] {
    return leafClusterTexture("birch-leaves", 256, seed + 6, {0.35f, 0.5f, 0.1f},
                              {0.1f, 0.22f, 0.03f}, 13);
  });
  int32_t shrubLeafTex = texture("shrub-leaves", 256, 256, [=] {
    return leafClusterTexture("shrub-leaves", 256, seed + 7, {0.12f, 0.3f, 0.06f},
                              {0.03f, 0.1f, 0.03f}, 17);
  });
  int32_t needleTex = texture("pine-needles", 256, 256, [=] {
    return needleTexture("pine-needles", 256, seed + 8, {0.08f, 0.2f, 0.06f},
                         {0.02f, 0.07f, 0.03f});
  });
  int32_t fernTex = texture("fern-frond", 256, 512, [=] {
    return frondTexture("fern-frond", 256, 512, seed + 9, {0.15f, 0.35f, 0.06f},
                        {0.04f, 0.13f, 0.02f}, 30, 0.45f);
  });
  int32_t petalTex = texture("petal", 128, 128, [=] {
    return petalTexture("petal", 128, {0.95f, 0.8f, 0.25f});
  });
  int32_t bladeTex = texture("grass-blade", 64, 256, [=] {
    return bladeTexture("grass-blade", 64, 256, seed + 10, {0.05f, 0.1f, 0.02f},
                        {0.35f, 0.45f, 0.12f});
  });
  int32_t rockTex = texture("rock", 256, 256, [=] {
    return rockTexture("rock", 256, seed + 11, {0.1f, 0.1f, 0.09f}, {0.38f, 0.37f, 0.34f});
  });

  // ------------------------------------------------------------ materials
  auto material = [&](const std::string& name, Vec3f colour, int32_t tex = kNoTexture,
                      bool alpha = false, float roughness = 0.9f) {
    Material m;
    m.name = name;
    m.baseColor = colour;
    m.baseColorTexture = tex;
    m.alphaTexture = alpha ? tex : kNoTexture;
    m.roughness = roughness;
    return plan.addMaterial(m);
  };
  const int32_t terrainMat = material("landscape-ground", Vec3f(1), terrainTex);
  const int32_t oakBark = material("oak-bark", Vec3f(1), oakBarkTex);
  const int32_t birchBark = material("birch-bark", Vec3f(1), birchBarkTex);
  const int32_t pineBark = material("pine-bark", Vec3f(1), pineBarkTex);
  const std::array<int32_t, 3> oakLeaves = {
      material("oak-leaves", Vec3f(1), oakLeafTex, true, 0.6f),
      material("oak-leaves-dark", Vec3f(0.7f), oakLeafTex, true, 0.6f),
      material("autumn-leaves", Vec3f(1), autumnLeafTex, true, 0.6f)};
  const int32_t birchLeaves = material("birch-leaves", Vec3f(1), birchLeafTex, true, 0.6f);
  const int32_t needles = material("pine-needles", Vec3f(1), needleTex, true, 0.7f);
  const int32_t shrubLeaves = material("shrub-leaves", Vec3f(1), shrubLeafTex, true, 0.6f);
  const int32_t fern = material("fern", Vec3f(1), fernTex, true, 0.7f);
  const int32_t grass = material("grass", Vec3f(1), bladeTex, false, 0.7f);
  const int32_t stem = material("flower-stem", {0.07f, 0.2f, 0.04f});
  const std::array<int32_t, 4> petals = {
      material("petal-white", {0.95f, 0.95f, 0.93f}, petalTex, true, 0.6f),
      material("petal-yellow", {1.0f, 0.82f, 0.15f}, petalTex, true, 0.6f),
      material("petal-purple", {0.5f, 0.2f, 0.75f}, petalTex, true, 0.6f),
      material("petal-red", {0.9f, 0.1f, 0.08f}, petalTex, true, 0.6f)};
  const int32_t flowerCentre = material("flower-centre", {0.85f, 0.6f, 0.05f});
  const int32_t rock = material("rock", Vec3f(1), rockTex, false, 0.8f);
  const int32_t logWood = material("log", {0.8f, 0.75f, 0.7f}, oakBarkTex);

  // ------------------------------------------------------------ terrain
  {
    MeshRecipe r;
    r.name = "landscape-terrain";
    r.material = terrainMat;
    r.counts = terrainCounts(grid);
    r.build = [grid, shape] {
      return buildTerrain(grid, [&](float x, float z) { return shape->height(x, z); });
    };
    plan.addSingleInstanceMesh(std::move(r));
  }

  // ------------------------------------------------------------ species
  const uint32_t speciesSeed = streamKey(seed, 0x1a4d);
  int speciesIndex = 0;
  auto add = [&](Species s) {
    addSpecies(plan, s, streamKey(speciesSeed, uint32_t(speciesIndex++)));
  };
  auto variantRng = [seed](uint32_t species, int v) {
    return HashRng(seed, 0x1a7a, species, uint32_t(v));
  };
  auto variantSeed = [seed](uint32_t species, int v) {
    return streamKey(seed, 0x1a7b, species, uint32_t(v));
  };

  {
    Species s;
    s.name = "oak";
    s.count = scaledCount(300, scale);
    s.variants = 16;
    s.design = [=](int v) {
      HashRng rng = variantRng(1, v);
      TreeParams p;
      p.trunkLength = rng.uniform(4.5f, 6);
      p.trunkRadius = rng.uniform(0.35f, 0.45f);
      p.trunkRings = 16;
      p.trunkSides = 12;
      p.levels = {{6 + v % 3, 10, 8, 0.9f, 0.5f, 55, 0.45f, 0.1f, 0.4f},
                  {4, 6, 6, 0.5f, 0.55f, 45, 0.3f, 0.15f, 0.4f},
                  {4, 4, 4, 0.5f, 0.55f, 40, 0.3f, 0.1f, 0.4f}};
      p.leavesPerTip = 24 + 2 * (v % 4);
      p.leafSegments = 2;
      p.leafSize = 1.0f;
      return designTree(p, variantSeed(1, v));
    };
    s.material = [=](PartRole r, int v) {
      return r == PartRole::Leaves ? oakLeaves[size_t(v) % 3] : oakBark;
    };
    s.rule = {6, 25, 0.8f, 1.2f, 3, 0, 0.1f, 24};
    s.ground = landscapeGround(shape, false, 4, 0.0f, 10);
    add(s);
  }
  {
    Species s;
    s.name = "pine";
    s.count = scaledCount(350, scale);
    s.variants = 16;
    s.design = [=](int v) {
      HashRng rng = variantRng(2, v);
      TreeParams p;
      p.trunkLength = rng.uniform(11, 16);
      p.trunkRadius = rng.uniform(0.2f, 0.3f);
      p.trunkRings = 20;
      p.trunkSides = 10;
      p.trunkTaper = 0.1f;
      p.trunkLean = 0.03f;
      p.trunkFlare = 0.3f;
      p.coneFactor = 0.9f;
      p.levels = {{34 + 2 * (v % 4), 6, 5, 0.35f, 0.3f, 95, 0.15f, -0.1f, 0.3f},
                  {3, 3, 3, 0.35f, 0.5f, 50, 0.3f, 0.0f, 0.4f}};
      p.leavesPerTip = 16;
      p.leafSegments = 1;
      p.leafSize = 0.9f;
      p.leafDroop = 0.1f;
      return designTree(p, variantSeed(2, v));
    };
    s.material = [=](PartRole r, int) { return r == PartRole::Leaves ? needles : pineBark; };
    s.rule = {8, 30, 0.8f, 1.2f, 2, 0, 0.1f, 24};
    s.ground = landscapeGround(shape, false, 4, 0.1f, 10);
    add(s);
  }
  {
    Species s;
    s.name = "birch";
    s.count = scaledCount(220, scale);
    s.variants = 14;
    s.design = [=](int v) {
      HashRng rng = variantRng(3, v);
      TreeParams p;
      p.trunkLength = rng.uniform(8, 11);
      p.trunkRadius = rng.uniform(0.12f, 0.17f);
      p.trunkRings = 16;
      p.trunkSides = 8;
      p.trunkTaper = 0.3f;
      p.trunkLean = rng.uniform(0.05f, 0.15f);
      p.levels = {{8, 8, 6, 0.4f, 0.5f, 35, 0.4f, 0.3f, 0.4f},
                  {4, 5, 4, 0.5f, 0.55f, 40, 0.3f, -0.2f, 0.4f},
                  {3, 4, 3, 0.5f, 0.55f, 40, 0.3f, -0.2f, 0.4f}};
      p.leavesPerTip = 20 + v % 5;
      p.leafSegments = 1;
      p.leafSize = 0.6f;
      return designTree(p, variantSeed(3, v));
    };
    s.material = [=](PartRole r, int) { return r == PartRole::Leaves ? birchLeaves : birchBark; };
    s.rule = {5, 15, 0.8f, 1.2f, 4, 0, 0.1f, 24};
    s.ground = landscapeGround(shape, false, 4, -0.1f, 10);
    add(s);
  }
  {
    Species s;
    s.name = "shrub";
    s.count = scaledCount(2000, scale);
    s.variants = 24;
    s.design = [=](int v) {
      HashRng rng = variantRng(4, v);
      TreeParams p;
      p.trunkLength = rng.uniform(0.3f, 0.6f);
      p.trunkRadius = 0.05f;
      p.trunkRings = 4;
      p.trunkSides = 5;
      p.trunkFlare = 0.2f;
      p.levels = {{4 + v % 3, 5, 4, 2.0f, 0.8f, 45, 0.2f, 0.3f, 0.4f},
                  {3, 4, 3, 0.5f, 0.6f, 40, 0.3f, 0.1f, 0.4f}};
      p.leavesPerTip = 24 + v % 8;
      p.leafSegments = 2;
      p.leafSize = 0.4f;
      return designTree(p, variantSeed(4, v));
    };
    s.material = [=](PartRole r, int) { return r == PartRole::Leaves ? shrubLeaves : oakBark; };
    s.rule = {10, 12, 0.6f, 1.3f, 6, 0.3f, 0.05f, 12};
    s.ground = landscapeGround(shape, false, 2, -10, 10);
    add(s);
  }
  {
    Species s;
    s.name = "fern";
    s.count = scaledCount(3000, scale);
    s.variants = 20;
    s.design = [=](int v) {
      HashRng rng = variantRng(5, v);
      FernParams p;
      p.fronds = 16 + v % 6;
      p.length = rng.uniform(0.7f, 1.2f);
      return designFern(p, variantSeed(5, v));
    };
    s.material = [=](PartRole, int) { return fern; };
    s.rule = {25, 8, 0.6f, 1.4f, 8, 0.5f, 0.03f, 16};
    s.ground = landscapeGround(shape, true, 1.6f, -0.05f, 10);
    add(s);
  }
  {
    Species s;
    s.name = "grass";
    s.count = scaledCount(26000, scale);
    s.variants = 40;
    s.design = [=](int v) {
      HashRng rng = variantRng(6, v);
      GrassParams p;
      p.blades = 96 + 4 * (v % 10);
      p.segments = 5;
      p.height = rng.uniform(0.35f, 0.8f);
      p.radius = rng.uniform(0.15f, 0.3f);
      return designGrass(p, variantSeed(6, v));
    };
    s.material = [=](PartRole, int) { return grass; };
    s.rule = {200, 15, 0.6f, 1.5f, 6, 0.7f, 0.02f, 16};
    s.ground = landscapeGround(shape, true, 1.5f, -10, 0.3f);
    add(s);
  }
  {
    Species s;
    s.name = "flower";
    s.count = scaledCount(7000, scale);
    s.variants = 30;
    s.design = [=](int v) {
      HashRng rng = variantRng(7, v);
      FlowerParams p;
      p.stems = 8 + v % 7;
      p.petals = 5 + v % 4;
      p.height = rng.uniform(0.25f, 0.6f);
      p.petalLength = rng.uniform(0.03f, 0.06f);
      return designFlowers(p, variantSeed(7, v));
    };
    s.material = [=](PartRole r, int v) {
      switch (r) {
        case PartRole::Petals:
          return petals[size_t(v) % 4];
        case PartRole::Leaves:
          return shrubLeaves;
        case PartRole::FlowerCentre:
          return flowerCentre;
        default:
          return stem;
      }
    };
    s.rule = {50, 5, 0.7f, 1.3f, 5, 0.6f, 0.02f, 16};
    s.ground = landscapeGround(shape, true, 1.5f, -10, 0.15f);
    add(s);
  }
  {
    Species s;
    s.name = "rock";
    s.count = scaledCount(700, scale);
    s.variants = 20;
    s.design = [=](int v) {
      HashRng rng = variantRng(8, v);
      RockParams p;
      p.detail = 12 + v % 8;
      p.radii = {rng.uniform(0.5f, 0.9f), rng.uniform(0.3f, 0.6f), rng.uniform(0.4f, 0.8f)};
      p.roughness = rng.uniform(0.2f, 0.35f);
      return designRock(p, variantSeed(8, v));
    };
    s.material = [=](PartRole, int) { return rock; };
    s.rule = {0, 0, 0.3f, 1.6f, 30, 0.8f, 0.1f, 12};
    s.ground = landscapeGround(shape, true, 2, -10, 10, 0.9f * kKnollHeight);
    add(s);
  }
  {
    Species s;
    s.name = "log";
    s.count = scaledCount(30, scale);
    s.variants = 6;
    s.design = [=](int v) {
      HashRng rng = variantRng(9, v);
      LogParams p;
      p.length = rng.uniform(3, 6);
      p.radius = rng.uniform(0.15f, 0.3f);
      return designLog(p, variantSeed(9, v));
    };
    s.material = [=](PartRole, int) { return logWood; };
    s.rule = {0, 0, 0.8f, 1.2f, 3, 1.0f, 0.05f, 24};
    s.ground = landscapeGround(shape, false, 3, 0.0f, 10);
    add(s);
  }

  // ------------------------------------------------------------ lights, views, bounds
  plan.suns.push_back({normalize(Vec3f(0.3f, 0.7f, 0.65f)), {5.5f, 5.2f, 4.8f}, 0.00465f});
  plan.environmentColor = {1, 1, 1};
  plan.environmentImage = [] {
    return skyGradient({0.2f, 0.38f, 0.78f}, {0.75f, 0.82f, 0.92f}, {0.28f, 0.27f, 0.24f}, 0.3f);
  };

  auto groundAt = [&](float x, float z) { return shape->height(x, z); };
  {
    CameraView v;
    v.name = "path";
    float x0 = 70, x1 = 35;
    float z0 = LandscapeShape::pathZ(x0), z1 = LandscapeShape::pathZ(x1);
    v.from = {x0, groundAt(x0, z0) + 1.7f, z0};
    v.at = {x1, groundAt(x1, z1) + 1.5f, z1};
    v.fovY = 45;
    plan.views.push_back(v);
  }
  {
    CameraView v;
    v.name = "view-3";
    Vec2f eye = LandscapeShape::kLookout;
    v.from = {eye.x, groundAt(eye.x, eye.y) + 6, eye.y};
    v.at = {shape->knoll.x, 0.45f * kKnollHeight, shape->knoll.y};
    v.fovY = 40;
    plan.views.push_back(v);
  }
  {
    CameraView v;
    v.name = "top";
    v.from = {0, 420, 0};
    v.at = {0, 0, 0};
    v.up = {0, 0, -1};
    v.fovY = 45;
    plan.views.push_back(v);
  }
  plan.bounds.extend(Vec3f(-kHalfSize, 0, -kHalfSize));
  plan.bounds.extend(Vec3f(kHalfSize, kKnollHeight, kHalfSize));
  return plan;
}

}  // namespace ferry::builtin
