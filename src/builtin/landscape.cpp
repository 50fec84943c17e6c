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

struct LandscapeTextures {
  int32_t terrain, oakBark, birchBark, pineBark, oakLeaves, autumnLeaves, birchLeaves, shrubLeaves,
      needles, fern, petal, blade, rock;
};

struct LandscapeMaterials {
  int32_t terrain, oakBark, birchBark, pineBark;
  std::array<int32_t, 3> oakLeaves;
  int32_t birchLeaves, needles, shrubLeaves, fern, grass, stem;
  std::array<int32_t, 4> petals;
  int32_t flowerCentre, rock, logWood;
};

// The random numbers that shape variant v of species `species`, and the key
// of its design.
struct VariantKeys {
  uint32_t seed;
  HashRng rng(uint32_t species, int v) const { return HashRng(seed, 0x1a7a, species, uint32_t(v)); }
  uint32_t design(uint32_t species, int v) const {
    return streamKey(seed, 0x1a7b, species, uint32_t(v));
  }
};

// Makes the landscape's plan one step at a time, in a fixed order: the
// indices of textures, materials, meshes and objects, and the species'
// random streams, depend on it. Every recipe captures what it needs by
// value: the planner is gone when the plan is materialized.
//
// The structure follows what is published of pbrt's landscape (L1 in
// docs/scenes.md): 29 objects of about 13 meshes each, 370 meshes, and per
// instance about 145 K triangles, because what is instanced is large: whole
// trees of 120-150 K triangles cut into a mesh per branch level and
// several leaf meshes, and ground cover baked into patches of a hundred and
// more clumps. The ground is one object of 15 x 15 tiles.
class LandscapePlanner {
 public:
  LandscapePlanner(double scale, uint32_t seed) : scale_(scale), seed_(seed), variants_{seed} {
    plan_.name = "landscape";
    grid_.x0 = grid_.z0 = -kHalfSize;
    grid_.x1 = grid_.z1 = kHalfSize;
    // A multiple of the tiles, 1,080 at scale 1 (the edges are at height 0
    // by the function's own fade, so no skirt is needed).
    const int cells = int(std::clamp(std::round(72 * std::sqrt(scale)), 4.0, 1024.0));
    grid_.segments = kGroundTiles * cells;
    shape_ = std::make_shared<const LandscapeShape>(seed, grid_);
  }

  ScenePlan plan() && {
    addMaterials(addTextures());
    addGround();
    addSpecies(plan_,
               {oaks(), autumnOaks(), pines(), birches(), grassPatches(), flowerPatches(),
                fernPatches(), shrubs(), saplings(), rocks(), logs()},
               streamKey(seed_, 0x1a4d));
    addLightsAndViews();
    plan_.bounds.extend(Vec3f(-kHalfSize, 0, -kHalfSize));
    plan_.bounds.extend(Vec3f(kHalfSize, kKnollHeight, kHalfSize));
    return std::move(plan_);
  }

 private:
  static constexpr int kGroundTiles = 15;

  LandscapeTextures addTextures();
  void addMaterials(const LandscapeTextures& tex);
  void addGround();
  Species oaks() const;
  Species autumnOaks() const;
  Species pines() const;
  Species birches() const;
  // A ground-cover species: one patch model (designPatch) whose clump k is
  // clump(rng, k, seed), each clump with its own random stream; patches kept
  // clear of the path by their reach (clumpReach: a clump's own radius).
  using ClumpDesign = std::function<PlantDesign(HashRng& rng, int clump, uint32_t seed)>;
  Species patches(std::string name, uint32_t species, double count, PatchParams patch,
                  ClumpDesign clump, float clumpReach, int clusterSize, float clusterRadius,
                  float forestMin, float forestMax) const;
  Species grassPatches() const;
  Species flowerPatches() const;
  Species fernPatches() const;
  Species shrubs() const;
  Species saplings() const;
  Species rocks() const;
  Species logs() const;
  void addLightsAndViews();

  const double scale_;
  const uint32_t seed_;
  const VariantKeys variants_;
  TerrainGrid grid_;
  Shape shape_;
  LandscapeMaterials mat_{};
  ScenePlan plan_;
};

LandscapeTextures LandscapePlanner::addTextures() {
  const uint32_t seed = seed_;
  auto texture = [&](std::string name, int w, int h, std::function<Texture()> build) {
    return plan_.addTexture({std::move(name), w, h, std::move(build)});
  };
  LandscapeTextures t;
  t.terrain = addTerrainTexture(
      plan_, "landscape-terrain", grid_, terrainTextureSize(1024 * std::sqrt(scale_) * 0.75),
      [shape = shape_, seed](float x, float z) { return groundColour(*shape, x, z, seed); });
  t.oakBark = texture("oak-bark", 256, 256, [=] {
    return barkTexture("oak-bark", 256, 256, seed + 1, {0.05f, 0.04f, 0.03f}, {0.22f, 0.18f, 0.13f},
                       BarkStyle::Furrowed);
  });
  t.birchBark = texture("birch-bark", 256, 256, [=] {
    return barkTexture("birch-bark", 256, 256, seed + 2, {0.04f, 0.035f, 0.03f},
                       {0.75f, 0.73f, 0.68f}, BarkStyle::Birch);
  });
  t.pineBark = texture("pine-bark", 256, 256, [=] {
    return barkTexture("pine-bark", 256, 256, seed + 3, {0.07f, 0.035f, 0.02f},
                       {0.3f, 0.16f, 0.09f}, BarkStyle::Furrowed);
  });
  t.oakLeaves = texture("oak-leaves", 256, 256, [=] {
    return leafClusterTexture("oak-leaves", 256, seed + 4, {0.2f, 0.36f, 0.07f},
                              {0.04f, 0.12f, 0.02f}, 9);
  });
  t.autumnLeaves = texture("autumn-leaves", 256, 256, [=] {
    return leafClusterTexture("autumn-leaves", 256, seed + 5, {0.75f, 0.35f, 0.05f},
                              {0.35f, 0.08f, 0.02f}, 9);
  });
  t.birchLeaves = texture("birch-leaves", 256, 256, [=] {
    return leafClusterTexture("birch-leaves", 256, seed + 6, {0.35f, 0.5f, 0.1f},
                              {0.1f, 0.22f, 0.03f}, 13);
  });
  t.shrubLeaves = texture("shrub-leaves", 256, 256, [=] {
    return leafClusterTexture("shrub-leaves", 256, seed + 7, {0.12f, 0.3f, 0.06f},
                              {0.03f, 0.1f, 0.03f}, 17);
  });
  t.needles = texture("pine-needles", 256, 256, [=] {
    return needleTexture("pine-needles", 256, seed + 8, {0.08f, 0.2f, 0.06f},
                         {0.02f, 0.07f, 0.03f});
  });
  t.fern = texture("fern-frond", 256, 512, [=] {
    return frondTexture("fern-frond", 256, 512, seed + 9, {0.15f, 0.35f, 0.06f},
                        {0.04f, 0.13f, 0.02f}, 30, 0.45f);
  });
  t.petal = texture("petal", 128, 128, [=] {
    return petalTexture("petal", 128, {0.95f, 0.8f, 0.25f});
  });
  t.blade = texture("grass-blade", 64, 256, [=] {
    return bladeTexture("grass-blade", 64, 256, seed + 10, {0.05f, 0.1f, 0.02f},
                        {0.35f, 0.45f, 0.12f});
  });
  t.rock = plan_.addTexture(
      {"rock", 256, 256, [=] {
         return rockTexture("rock", 256, seed + 11, {0.1f, 0.1f, 0.09f}, {0.38f, 0.37f, 0.34f});
       }});
  return t;
}

void LandscapePlanner::addMaterials(const LandscapeTextures& tex) {
  auto material = [&](const char* name, Vec3f colour, int32_t texture = kNoTexture,
                      bool alphaCutout = false) {
    return addDiffuseMaterial(plan_, name, colour, texture, alphaCutout);
  };
  LandscapeMaterials& mat = mat_;
  mat.terrain = material("landscape-ground", Vec3f(1), tex.terrain);
  mat.oakBark = material("oak-bark", Vec3f(1), tex.oakBark);
  mat.birchBark = material("birch-bark", Vec3f(1), tex.birchBark);
  mat.pineBark = material("pine-bark", Vec3f(1), tex.pineBark);
  mat.oakLeaves = {material("oak-leaves", Vec3f(1), tex.oakLeaves, true),
                   material("oak-leaves-dark", Vec3f(0.7f), tex.oakLeaves, true),
                   material("autumn-leaves", Vec3f(1), tex.autumnLeaves, true)};
  mat.birchLeaves = material("birch-leaves", Vec3f(1), tex.birchLeaves, true);
  mat.needles = material("pine-needles", Vec3f(1), tex.needles, true);
  mat.shrubLeaves = material("shrub-leaves", Vec3f(1), tex.shrubLeaves, true);
  mat.fern = material("fern", Vec3f(1), tex.fern, true);
  mat.grass = material("grass", Vec3f(1), tex.blade);
  mat.stem = material("flower-stem", {0.07f, 0.2f, 0.04f});
  mat.petals = {material("petal-white", {0.95f, 0.95f, 0.93f}, tex.petal, true),
                material("petal-yellow", {1.0f, 0.82f, 0.15f}, tex.petal, true),
                material("petal-purple", {0.5f, 0.2f, 0.75f}, tex.petal, true),
                material("petal-red", {0.9f, 0.1f, 0.08f}, tex.petal, true)};
  mat.flowerCentre = material("flower-centre", {0.85f, 0.6f, 0.05f});
  mat.rock = material("rock", Vec3f(1), tex.rock);
  mat.logWood = material("log", {0.8f, 0.75f, 0.7f}, tex.oakBark);
}

void LandscapePlanner::addGround() {
  std::vector<int32_t> tiles;
  for (int tj = 0; tj < kGroundTiles; ++tj)
    for (int ti = 0; ti < kGroundTiles; ++ti)
      tiles.push_back(plan_.addMesh(
          terrainTileRecipe(fmt::format("ground/tile-{}-{}", ti, tj), mat_.terrain, grid_,
                            terrainTile(grid_, kGroundTiles, ti, tj),
                            [shape = shape_](float x, float z) { return shape->height(x, z); })));
  int32_t ground = plan_.addObject("ground", std::move(tiles));
  plan_.addInstances(ground, 1, [](uint64_t) { return Affine3f::identity(); });
}

// A broadleaf tree of about 143 K triangles: four branch levels, 420 tips.
TreeParams oakParams(HashRng& rng, int v) {
  TreeParams p;
  p.trunkLength = rng.uniform(4.5f, 6);
  p.trunkRadius = rng.uniform(0.35f, 0.45f);
  p.trunkRings = 16;
  p.trunkSides = 12;
  p.levels = {{7, 10, 8, 0.9f, 0.5f, 55, 0.45f, 0.1f, 0.4f},
              {5, 6, 6, 0.5f, 0.55f, 45, 0.3f, 0.15f, 0.4f},
              {4, 4, 4, 0.55f, 0.55f, 40, 0.3f, 0.1f, 0.4f},
              {3, 3, 3, 0.6f, 0.55f, 40, 0.3f, 0.1f, 0.4f}};
  p.leavesPerTip = 78 + 2 * (v % 3);
  p.leafSegments = 2;
  p.leafSize = 0.42f;
  p.woodByLevel = true;
  p.leafMeshes = 8;
  return p;
}

Species LandscapePlanner::oaks() const {
  Species s;
  s.name = "oak";
  s.count = scaledCount(420, scale_);
  s.variants = 1;
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(1, v);
    return designTree(oakParams(rng, v), keys.design(1, v));
  };
  s.material = [leaves = mat_.oakLeaves, bark = mat_.oakBark](const PlantPart& part, int) {
    return part.role == PartRole::Leaves ? leaves[size_t(part.group) % 2] : bark;
  };
  s.rule = {6, 25, 0.8f, 1.2f, 3, 0, 0.1f, 24};
  s.ground = landscapeGround(shape_, false, 4, 0.0f, 10);
  return s;
}

Species LandscapePlanner::autumnOaks() const {
  Species s = oaks();
  s.name = "oak-autumn";
  s.count = scaledCount(50, scale_);
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(10, v);
    return designTree(oakParams(rng, v + 1), keys.design(10, v));
  };
  s.material = [leaves = mat_.oakLeaves[2], bark = mat_.oakBark](const PlantPart& part, int) {
    return part.role == PartRole::Leaves ? leaves : bark;
  };
  s.rule = {0, 0, 0.8f, 1.2f, 3, 0, 0.1f, 24};
  return s;
}

Species LandscapePlanner::pines() const {
  Species s;
  s.name = "pine";
  s.count = scaledCount(600, scale_);
  s.variants = 1;
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(2, v);
    TreeParams p;
    p.trunkLength = rng.uniform(11, 16);
    p.trunkRadius = rng.uniform(0.2f, 0.3f);
    p.trunkRings = 20;
    p.trunkSides = 10;
    p.trunkTaper = 0.1f;
    p.trunkLean = 0.03f;
    p.trunkFlare = 0.3f;
    p.coneFactor = 0.9f;
    p.levels = {{36, 6, 5, 0.35f, 0.3f, 95, 0.15f, -0.1f, 0.3f},
                {3, 3, 3, 0.35f, 0.5f, 50, 0.3f, 0.0f, 0.4f},
                {3, 2, 3, 0.5f, 0.5f, 45, 0.3f, 0.0f, 0.4f}};
    p.leavesPerTip = 90;
    p.leafSegments = 2;
    p.leafSize = 0.5f;
    p.leafDroop = 0.1f;
    p.woodByLevel = true;
    p.leafMeshes = 9;
    return designTree(p, keys.design(2, v));
  };
  s.material = [needles = mat_.needles, bark = mat_.pineBark](const PlantPart& part, int) {
    return part.role == PartRole::Leaves ? needles : bark;
  };
  s.rule = {8, 30, 0.8f, 1.2f, 2, 0, 0.1f, 24};
  s.ground = landscapeGround(shape_, false, 4, 0.1f, 10);
  return s;
}

Species LandscapePlanner::birches() const {
  Species s;
  s.name = "birch";
  s.count = scaledCount(390, scale_);
  s.variants = 1;
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(3, v);
    TreeParams p;
    p.trunkLength = rng.uniform(8, 11);
    p.trunkRadius = rng.uniform(0.12f, 0.17f);
    p.trunkRings = 16;
    p.trunkSides = 8;
    p.trunkTaper = 0.3f;
    p.trunkLean = rng.uniform(0.05f, 0.15f);
    p.levels = {{8, 8, 6, 0.4f, 0.5f, 35, 0.4f, 0.3f, 0.4f},
                {5, 5, 4, 0.5f, 0.55f, 40, 0.3f, -0.2f, 0.4f},
                {4, 4, 3, 0.5f, 0.55f, 40, 0.3f, -0.2f, 0.4f},
                {3, 3, 3, 0.55f, 0.55f, 40, 0.3f, -0.2f, 0.4f}};
    p.leavesPerTip = 60;
    p.leafSegments = 2;
    p.leafSize = 0.3f;
    p.woodByLevel = true;
    p.leafMeshes = 8;
    return designTree(p, keys.design(3, v));
  };
  s.material = [leaves = mat_.birchLeaves, bark = mat_.birchBark](const PlantPart& part, int) {
    return part.role == PartRole::Leaves ? leaves : bark;
  };
  s.rule = {5, 15, 0.8f, 1.2f, 4, 0, 0.1f, 24};
  s.ground = landscapeGround(shape_, false, 4, -0.1f, 10);
  return s;
}

// Patches follow the ground's slope at their centre and sink a little, so
// their rims stay on the ground where it curves.
constexpr float kPatchSlopeAlign = 1;
constexpr float kPatchSink = 0.08f;
constexpr float kPatchScaleMin = 0.8f, kPatchScaleMax = 1.2f;

// How far a patch's centre keeps from the path's centre line so that none of
// it reaches the path: its disc at the largest scale, and its clumps' reach.
float patchClearance(float radius, float clumpReach) {
  return (radius + clumpReach) * kPatchScaleMax + kPathHalfWidth;
}

Species LandscapePlanner::patches(std::string name, uint32_t species, double count,
                                  PatchParams patch, ClumpDesign clump, float clumpReach,
                                  int clusterSize, float clusterRadius, float forestMin,
                                  float forestMax) const {
  Species s;
  s.name = std::move(name);
  s.count = scaledCount(count, scale_);
  s.variants = 1;
  s.design = [keys = variants_, species, patch, clump](int v) {
    return designPatch(
        patch,
        [keys, species, v, clump](int k) {
          HashRng rng = keys.rng(species, v * 1000 + k);
          return clump(rng, k, keys.design(species, v * 1000 + k));
        },
        keys.design(species, 999));
  };
  s.rule = {clusterSize, clusterRadius,    kPatchScaleMin, kPatchScaleMax,
            0,           kPatchSlopeAlign, kPatchSink,     16};
  s.ground =
      landscapeGround(shape_, true, patchClearance(patch.radius, clumpReach), forestMin, forestMax);
  return s;
}

Species LandscapePlanner::grassPatches() const {
  Species s = patches(
      "grass-patch", 6, 1350, {.radius = 4, .clumps = 220, .groups = 13},
      [](HashRng& rng, int k, uint32_t seed) {
        GrassParams p;
        p.blades = 56 + 2 * (k % 10);
        p.segments = 5;
        p.height = rng.uniform(0.35f, 0.8f);
        p.radius = rng.uniform(0.15f, 0.3f);
        return designGrass(p, seed);
      },
      0.4f, 0, 0, -10, 0.3f);
  s.material = [grass = mat_.grass](const PlantPart&, int) { return grass; };
  return s;
}

Species LandscapePlanner::flowerPatches() const {
  Species s = patches(
      "flower-patch", 7, 290, {.radius = 2.5f, .clumps = 120, .groups = 3},
      [](HashRng& rng, int k, uint32_t seed) {
        FlowerParams p;
        p.stems = 8 + k % 7;
        p.petals = 5 + k % 4;
        p.height = rng.uniform(0.25f, 0.6f);
        p.petalLength = rng.uniform(0.03f, 0.06f);
        return designFlowers(p, seed);
      },
      0.3f, 5, 8, -10, 0.15f);
  s.material = [mat = mat_](const PlantPart& part, int) {
    switch (part.role) {
      case PartRole::Petals:
        return mat.petals[size_t(part.group) % 4];
      case PartRole::Leaves:
        return mat.shrubLeaves;
      case PartRole::FlowerCentre:
        return mat.flowerCentre;
      default:
        return mat.stem;
    }
  };
  return s;
}

Species LandscapePlanner::fernPatches() const {
  Species s = patches(
      "fern-patch", 5, 290, {.radius = 3, .clumps = 120, .groups = 7},
      [](HashRng& rng, int k, uint32_t seed) {
        FernParams p;
        p.fronds = 16 + k % 6;
        p.length = rng.uniform(0.7f, 1.2f);
        return designFern(p, seed);
      },
      1.0f, 4, 10, -0.05f, 10);
  s.material = [fern = mat_.fern](const PlantPart&, int) { return fern; };
  return s;
}

Species LandscapePlanner::shrubs() const {
  Species s;
  s.name = "shrub";
  s.count = scaledCount(100, scale_);
  s.variants = 8;
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(4, v);
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
    p.woodByLevel = true;
    return designTree(p, keys.design(4, v));
  };
  s.material = [leaves = mat_.shrubLeaves, bark = mat_.oakBark](const PlantPart& part, int) {
    return part.role == PartRole::Leaves ? leaves : bark;
  };
  s.rule = {5, 12, 0.6f, 1.3f, 6, 0.3f, 0.05f, 12};
  s.ground = landscapeGround(shape_, false, 2, -10, 10);
  return s;
}

// Young birches and pines at the forest's edge.
Species LandscapePlanner::saplings() const {
  Species s;
  s.name = "sapling";
  s.count = scaledCount(60, scale_);
  s.variants = 4;
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(11, v);
    TreeParams p;
    p.trunkLength = rng.uniform(2.5f, 4);
    p.trunkRadius = rng.uniform(0.05f, 0.08f);
    p.trunkRings = 10;
    p.trunkSides = 6;
    p.trunkTaper = 0.3f;
    p.levels = {{6, 6, 4, 0.45f, 0.5f, 40, 0.4f, 0.2f, 0.4f},
                {3, 4, 3, 0.5f, 0.55f, 40, 0.3f, -0.1f, 0.4f}};
    p.leavesPerTip = 30;
    p.leafSegments = 2;
    p.leafSize = 0.3f;
    p.woodByLevel = true;
    p.leafMeshes = 2;
    return designTree(p, keys.design(11, v));
  };
  s.material = [mat = mat_](const PlantPart& part, int v) {
    if (part.role != PartRole::Leaves) return v % 2 ? mat.pineBark : mat.birchBark;
    return v % 2 ? mat.needles : mat.birchLeaves;
  };
  s.rule = {0, 0, 0.8f, 1.2f, 4, 0, 0.05f, 24};
  s.ground = landscapeGround(shape_, false, 3, -0.2f, 0.1f);
  return s;
}

Species LandscapePlanner::rocks() const {
  Species s;
  s.name = "rock";
  s.count = scaledCount(90, scale_);
  s.variants = 6;
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(8, v);
    RockParams p;
    p.detail = 14 + v;
    p.radii = {rng.uniform(0.5f, 0.9f), rng.uniform(0.3f, 0.6f), rng.uniform(0.4f, 0.8f)};
    p.roughness = rng.uniform(0.2f, 0.35f);
    return designRock(p, keys.design(8, v));
  };
  s.material = [rock = mat_.rock](const PlantPart&, int) { return rock; };
  s.rule = {0, 0, 0.3f, 1.6f, 30, 0.8f, 0.1f, 12};
  s.ground = landscapeGround(shape_, true, 2, -10, 10, 0.9f * kKnollHeight);
  return s;
}

Species LandscapePlanner::logs() const {
  Species s;
  s.name = "log";
  s.count = scaledCount(20, scale_);
  s.variants = 3;
  s.design = [keys = variants_](int v) {
    HashRng rng = keys.rng(9, v);
    LogParams p;
    p.length = rng.uniform(3, 6);
    p.radius = rng.uniform(0.15f, 0.3f);
    return designLog(p, keys.design(9, v));
  };
  s.material = [wood = mat_.logWood](const PlantPart&, int) { return wood; };
  s.rule = {0, 0, 0.8f, 1.2f, 3, 1.0f, 0.05f, 24};
  s.ground = landscapeGround(shape_, false, 3, 0.0f, 10);
  return s;
}

void LandscapePlanner::addLightsAndViews() {
  addDaylight(plan_, {0.3f, 0.7f, 0.65f}, {0.2f, 0.38f, 0.78f}, {0.75f, 0.82f, 0.92f},
              {0.28f, 0.27f, 0.24f}, 0.3f);
  auto groundAt = [shape = shape_](float x, float z) { return shape->height(x, z); };
  // Along the path, looking ahead down it.
  const float x0 = 70, x1 = 35;
  const float z0 = LandscapeShape::pathZ(x0), z1 = LandscapeShape::pathZ(x1);
  plan_.views.push_back({.name = "path",
                         .from = {x0, groundAt(x0, z0) + 1.7f, z0},
                         .at = {x1, groundAt(x1, z1) + 1.5f, z1},
                         .fovY = 45});
  const Vec2f eye = LandscapeShape::kLookout, knoll = shape_->knoll;
  plan_.views.push_back({.name = "view-3",
                         .from = {eye.x, groundAt(eye.x, eye.y) + 6, eye.y},
                         .at = {knoll.x, 0.45f * kKnollHeight, knoll.y},
                         .fovY = 40});
  plan_.views.push_back(
      {.name = "top", .from = {0, 420, 0}, .at = {0, 0, 0}, .up = {0, 0, -1}, .fovY = 45});
}

}  // namespace

ScenePlan planLandscape(double scale, uint32_t seed) {
  return LandscapePlanner(scale, seed).plan();
}

}  // namespace ferry::builtin
