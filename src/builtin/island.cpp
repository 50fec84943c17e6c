#include "builtin/island.h"

#include <array>
#include <cmath>
#include <map>
#include <memory>

#include <fmt/format.h>

#include "builtin/island_elements.h"
#include "builtin/island_shape.h"
#include "builtin/island_terrain.h"
#include "builtin/noise.h"
#include "builtin/plants.h"
#include "builtin/procedural_texture.h"
#include "builtin/terrain.h"
#include "builtin/vegetation.h"
#include "material/models/dielectric.h"

namespace ferry::builtin {
namespace {

constexpr int kGroundTiles = 16;  // per side
constexpr int kPeakSectors = 8;
constexpr int kBeachPieces = 3;
constexpr int kReefMounds = 8;

float scaledResolution(float base, double scale, int lo, int hi) {
  double v = std::round(double(base) * std::sqrt(scale));
  return float(std::clamp(v, double(lo), double(hi)));
}

// The smallest multiple of `multiple` at least `base` sqrt(scale), within [lo, hi].
int scaledMultiple(float base, double scale, int multiple, int lo, int hi) {
  int v = int(scaledResolution(base, scale, lo, hi));
  return std::max(multiple, (v + multiple - 1) / multiple * multiple);
}

struct IslandTextures {
  int32_t terrain, rock, sand, bark, leaves, giantLeaves, palmBark, palmFronds, fern, grass, petal;
};

// Roles to materials for the plants; some kinds override a role.
struct IslandMaterials {
  int32_t terrain, sand, rock, ocean, seabed, bark, leaves, palmBark, palmFronds, deadFronds,
      coconut, fern, grass, seaweed, stem, flowerCentre, driftwood, shell, giantBark, giantLeaves,
      lanternGlow, flame, lanternPole;
  std::array<int32_t, 3> petals, corals;

  int32_t forPlantPart(PartRole role) const {
    switch (role) {
      case PartRole::Wood:
        return bark;
      case PartRole::Leaves:
        return leaves;
      case PartRole::Fronds:
        return palmFronds;
      case PartRole::Fruit:
        return coconut;
      case PartRole::Blades:
        return grass;
      case PartRole::Stems:
        return stem;
      case PartRole::Petals:
        return petals[0];
      case PartRole::FlowerCentre:
        return flowerCentre;
      case PartRole::Rock:
      default:
        return rock;
    }
  }

  int32_t forKind(PlantKind kind, PartRole role, int v) const {
    switch (kind) {
      case PlantKind::Palm:
      case PlantKind::Pandanus:
        return role == PartRole::Wood ? palmBark : forPlantPart(role);
      case PlantKind::DeadPalm:
        return role == PartRole::Wood ? palmBark : role == PartRole::Fronds ? deadFronds : coconut;
      case PlantKind::Fern:
        return fern;
      case PlantKind::Seaweed:
        return seaweed;
      case PlantKind::Flowers:
        return role == PartRole::Petals ? petals[size_t(v) % 3] : forPlantPart(role);
      case PlantKind::Shell:
        return shell;
      case PlantKind::Debris:
        return driftwood;
      case PlantKind::AntlerCoral:
      case PlantKind::CabbageCoral:
        return corals[size_t(v) % 3];
      default:
        return forPlantPart(role);
    }
  }
};

// Makes the island's plan one step at a time, in a fixed order: the indices
// of textures, materials, meshes and objects, and the species' random
// streams, depend on it. Every recipe captures what it needs by value: the
// planner is gone when the plan is materialized.
class IslandPlanner {
 public:
  IslandPlanner(double scale, uint32_t seed)
      : scale_(scale),
        seed_(seed),
        variantFactor_(
            std::clamp(scale >= 1 ? std::floor(std::sqrt(scale)) : std::sqrt(scale), 0.0, 32.0)),
        shape_(std::make_shared<const IslandShape>(seed)) {
    plan_.name = "island";
    grid_.x0 = grid_.z0 = -kGroundHalfSize;
    grid_.x1 = grid_.z1 = kGroundHalfSize;
    grid_.segments = kGroundTiles * int(scaledResolution(32, scale, 4, 512));
  }

  ScenePlan plan() && {
    addMaterials(addTextures());
    ElementMeshes base;
    addGroundTiles(plan_, shape_, grid_, kGroundTiles, mat_.terrain, base);
    const int rings = int(scaledResolution(48, scale_, 12, 2048));
    const int segments = scaledMultiple(192, scale_, kPeakSectors, 48, 8192);
    addPeak(plan_, shape_, 0, grid_, rings, segments, kPeakSectors, mat_.terrain, "isMountainA",
            base);
    addPeak(plan_, shape_, 1, grid_, std::max(8, rings * 2 / 3),
            scaledMultiple(128, scale_, kPeakSectors, 48, 8192), kPeakSectors, mat_.terrain,
            "isMountainB", base);
    addCliffs(plan_, shape_, int(scaledResolution(48, scale_, 8, 1024)), mat_.rock, base);
    addBeach(plan_, shape_, scaledMultiple(480, scale_, kBeachPieces, 33, 8193),
             int(scaledResolution(48, scale_, 6, 1024)), kBeachPieces, mat_.sand, base);
    addReefMounds(plan_, shape_, kReefMounds, int(scaledResolution(20, scale_, 4, 512)), seed_,
                  mat_.rock, base);
    addSea(plan_, mat_.ocean, mat_.seabed, base);
    // Each element's base geometry is one object of its meshes, placed once.
    for (const char* element : kIslandElements) {
      auto it = base.find(element);
      if (it == base.end()) continue;
      int32_t o = plan_.addObject(std::string(element) + "/base", it->second);
      plan_.addInstances(o, 1, [](uint64_t) { return Affine3f::identity(); });
    }
    addCampfire();
    addLanterns();
    addGiantIronwood();
    addElementSpecies();
    addLightsAndViews();
    plan_.bounds.extend(Vec3f(-kOceanHalfSize, kSeabed, -kOceanHalfSize));
    plan_.bounds.extend(Vec3f(kOceanHalfSize, kPeakHeight, kOceanHalfSize));
    return std::move(plan_);
  }

 private:
  IslandTextures addTextures();
  void addMaterials(const IslandTextures& tex);
  void addCampfire();
  void addLanterns();
  void addGiantIronwood();
  void addElementSpecies();
  void addLightsAndViews();

  const double scale_;
  const uint32_t seed_;
  // Species have more variants in larger scenes, fewer (at least one) in smaller ones.
  const double variantFactor_;
  const Shape shape_;
  TerrainGrid grid_;
  IslandMaterials mat_{};
  ScenePlan plan_;
};

IslandTextures IslandPlanner::addTextures() {
  const uint32_t seed = seed_;
  auto texture = [&](std::string name, int w, int h, std::function<Texture()> build) {
    return plan_.addTexture({std::move(name), w, h, std::move(build)});
  };
  IslandTextures t;
  // The size is computed in float (the landscape's in double): near a power of
  // two the two can differ, and the island has always used float.
  t.terrain = addTerrainTexture(
      plan_, "island-terrain", grid_, terrainTextureSize(1024 * float(std::sqrt(scale_)) * 0.75f),
      [shape = shape_, seed](float x, float z) { return groundColour(*shape, x, z, seed); });
  t.rock = texture("island-rock", 512, 512, [=] {
    return rockTexture("island-rock", 512, seed + 1, {0.09f, 0.085f, 0.08f}, {0.32f, 0.3f, 0.27f});
  });
  t.sand = texture("island-sand", 256, 256, [=] {
    return sandTexture("island-sand", 256, seed + 2, {0.26f, 0.21f, 0.14f}, {0.42f, 0.35f, 0.24f});
  });
  t.bark = texture("island-bark", 256, 256, [=] {
    return barkTexture("island-bark", 256, 256, seed + 3, {0.05f, 0.035f, 0.025f},
                       {0.25f, 0.19f, 0.13f}, BarkStyle::Furrowed);
  });
  t.leaves = texture("island-leaves", 512, 512, [=] {
    return leafClusterTexture("island-leaves", 512, seed + 4, {0.16f, 0.36f, 0.06f},
                              {0.03f, 0.11f, 0.02f}, 11);
  });
  t.giantLeaves = texture("giant-ironwood-leaves", 512, 512, [=] {
    return leafClusterTexture("giant-ironwood-leaves", 512, seed + 5, {0.1f, 0.26f, 0.05f},
                              {0.02f, 0.07f, 0.015f}, 15);
  });
  t.palmBark = texture("palm-bark", 256, 256, [=] {
    return barkTexture("palm-bark", 256, 256, seed + 6, {0.12f, 0.09f, 0.06f},
                       {0.42f, 0.35f, 0.25f}, BarkStyle::PalmRings);
  });
  t.palmFronds = texture("palm-frond", 256, 1024, [=] {
    return frondTexture("palm-frond", 256, 1024, seed + 7, {0.22f, 0.4f, 0.08f},
                        {0.06f, 0.15f, 0.03f}, 70, 0.5f);
  });
  t.fern = texture("fern-frond", 256, 512, [=] {
    return frondTexture("fern-frond", 256, 512, seed + 8, {0.12f, 0.33f, 0.05f},
                        {0.03f, 0.12f, 0.02f}, 34, 0.45f);
  });
  t.grass = texture("grass-blade", 64, 256, [=] {
    return bladeTexture("grass-blade", 64, 256, seed + 9, {0.05f, 0.12f, 0.02f},
                        {0.3f, 0.45f, 0.1f});
  });
  t.petal = texture("petal", 128, 128, [=] {
    return petalTexture("petal", 128, {0.9f, 0.75f, 0.2f});
  });
  return t;
}

void IslandPlanner::addMaterials(const IslandTextures& tex) {
  auto material = [&](const char* name, Vec3f colour, int32_t texture = kNoTexture,
                      bool alphaCutout = false) {
    return addDiffuseMaterial(plan_, name, colour, texture, alphaCutout);
  };
  IslandMaterials& mat = mat_;
  mat.terrain = material("island-ground", Vec3f(1), tex.terrain);
  mat.sand = material("beach-sand", Vec3f(1), tex.sand);
  mat.rock = material("rock", Vec3f(1), tex.rock);
  Material water;
  water.name = "ocean";
  water.baseColor = {0.9f, 0.97f, 1.0f};
  // Slightly rough: light reaches a diffuse seabed under a perfectly smooth
  // surface only by caustic paths, which a path tracer with light sampling
  // finds by chance (white speckles on black); a rough surface takes light
  // samples itself, so the sea reads as sky and sun reflected on dark water.
  water.model = std::make_shared<DielectricModel>(1.33f, 0.12f);
  mat.ocean = plan_.addMaterial(water);
  mat.seabed = material("seabed", kDeepSeabed);
  mat.bark = material("bark", Vec3f(1), tex.bark);
  mat.leaves = material("leaves", Vec3f(1), tex.leaves, true);
  mat.palmBark = material("palm-bark", Vec3f(1), tex.palmBark);
  mat.palmFronds = material("palm-fronds", Vec3f(1), tex.palmFronds, true);
  mat.deadFronds = material("dead-palm-fronds", {1.0f, 0.75f, 0.45f}, tex.palmFronds, true);
  mat.coconut = material("coconut", {0.22f, 0.15f, 0.07f});
  mat.fern = material("fern", Vec3f(1), tex.fern, true);
  mat.grass = material("grass", Vec3f(1), tex.grass);
  mat.seaweed = material("seaweed", {0.45f, 0.4f, 0.2f}, tex.grass);
  mat.stem = material("flower-stem", {0.08f, 0.22f, 0.04f});
  mat.petals = {material("petal-red", {1.0f, 0.12f, 0.15f}, tex.petal, true),
                material("petal-yellow", {1.0f, 0.85f, 0.2f}, tex.petal, true),
                material("petal-white", {0.95f, 0.95f, 0.92f}, tex.petal, true)};
  mat.flowerCentre = material("flower-centre", {0.8f, 0.5f, 0.05f});
  mat.driftwood = material("driftwood", {0.9f, 0.88f, 0.85f}, tex.bark);
  mat.shell = material("shell", {0.85f, 0.8f, 0.72f});
  mat.corals = {material("coral-pink", {0.75f, 0.35f, 0.4f}, tex.rock),
                material("coral-orange", {0.85f, 0.5f, 0.25f}, tex.rock),
                material("coral-violet", {0.45f, 0.3f, 0.6f}, tex.rock)};
  mat.giantBark = material("giant-ironwood-bark", {0.85f, 0.82f, 0.78f}, tex.bark);
  mat.giantLeaves = material("giant-ironwood-leaves", Vec3f(1), tex.giantLeaves, true);
  Material glow;
  glow.name = "lantern-glow";
  glow.baseColor = {0.8f, 0.7f, 0.5f};
  glow.emission = {6.0f, 4.0f, 1.5f};
  mat.lanternGlow = plan_.addMaterial(glow);
  Material fire;
  fire.name = "campfire-flame";
  fire.baseColor = {0.8f, 0.5f, 0.2f};
  fire.emission = {8.0f, 3.0f, 0.7f};
  mat.flame = plan_.addMaterial(fire);
  mat.lanternPole = material("lantern-pole", {0.2f, 0.13f, 0.07f});
}

void IslandPlanner::addCampfire() {
  const Vec2f at = shape_->campfire;
  const float y = shape_->surface(at.x, at.y);
  const uint32_t seed = seed_;
  MeshRecipe flame;
  flame.name = "isBeach/campfire-flame";
  flame.material = mat_.flame;
  flame.counts = cubeSphereCounts(4);
  flame.build = [at, y] {
    MeshBuilder b(true, true, cubeSphereCounts(4));
    addCubeSphere(b, 4, [&](Vec3f d) {
      float taper = 1 - 0.6f * std::max(0.0f, d.y);  // a flame narrows upwards
      return Vec3f(at.x + 0.3f * d.x * taper, y + 0.45f + 0.5f * d.y, at.y + 0.3f * d.z * taper);
    });
    return b.finish();
  };
  MeshRecipe stones;
  stones.name = "isBeach/campfire-stones";
  stones.material = mat_.rock;
  stones.counts = cubeSphereCounts(3) * 9;
  stones.build = [at, y, seed] {
    MeshBuilder b(true, true, cubeSphereCounts(3) * 9);
    for (int k = 0; k < 9; ++k) {
      float a = 2 * kPi * float(k) / 9;
      Vec3f c{at.x + 0.75f * std::cos(a), y, at.y + 0.75f * std::sin(a)};
      RockParams rp;
      rp.radii = {0.22f, 0.15f, 0.18f};
      addCubeSphere(b, 3, [&](Vec3f d) { return c + rockSurface(rp, seed + uint32_t(k), d); });
    }
    return b.finish();
  };
  int32_t f = plan_.addMesh(std::move(flame));
  int32_t s = plan_.addMesh(std::move(stones));
  int32_t o = plan_.addObject("isBeach/campfire", {f, s});
  plan_.addInstances(o, 1, [](uint64_t) { return Affine3f::identity(); });
}

void IslandPlanner::addLanterns() {
  for (size_t k = 0; k < shape_->lanterns.size(); ++k) {
    const Vec2f at = shape_->lanterns[k];
    const float y = shape_->surface(at.x, at.y);
    MeshRecipe pole;
    pole.name = fmt::format("isBeach/lantern-{}-pole", k);
    pole.material = mat_.lanternPole;
    pole.counts = tubeCounts(2, 6);
    pole.build = [at, y] {
      MeshBuilder b(true, true, tubeCounts(2, 6));
      Vec3f pts[2] = {{at.x, y - 0.3f, at.y}, {at.x, y + 2.0f, at.y}};
      float radii[2] = {0.04f, 0.03f};
      addTube(b, pts, radii, 6);
      return b.finish();
    };
    MeshRecipe glow;
    glow.name = fmt::format("isBeach/lantern-{}-glow", k);
    glow.material = mat_.lanternGlow;
    glow.counts = cubeSphereCounts(3);
    glow.build = [at, y] {
      MeshBuilder b(true, true, cubeSphereCounts(3));
      Vec3f c{at.x, y + 2.2f, at.y};
      addCubeSphere(b, 3, [&](Vec3f d) { return c + Vec3f(d.x, d.y * 1.3f, d.z) * 0.16f; });
      return b.finish();
    };
    int32_t p = plan_.addMesh(std::move(pole));
    int32_t g = plan_.addMesh(std::move(glow));
    int32_t o = plan_.addObject(fmt::format("isBeach/lantern-{}", k), {p, g});
    plan_.addInstances(o, 1, [](uint64_t) { return Affine3f::identity(); });
  }
}

// isIronwoodA1's own tree: a giant with aerial roots, far larger than any
// other plant (its geometry is the largest of the original's elements; see
// docs/scenes.md). The first copy stands where the default view sees it.
void IslandPlanner::addGiantIronwood() {
  TreeParams giant;
  giant.trunkLength = 9;
  giant.trunkRadius = 1.4f;
  giant.trunkRings = 40;
  giant.trunkSides = 32;
  giant.trunkTaper = 0.5f;
  giant.trunkLean = 0.05f;
  giant.trunkFlare = 0.8f;
  giant.levels = {{12, 24, 16, 1.5f, 0.45f, 70, 0.55f, 0.05f, 0.35f},
                  {6, 12, 10, 0.5f, 0.5f, 45, 0.2f, 0.3f, 0.4f},
                  {5, 8, 6, 0.5f, 0.5f, 40, 0.3f, 0.2f, 0.4f},
                  {4, 5, 4, 0.5f, 0.5f, 40, 0.3f, 0.15f, 0.4f}};
  // Below scale 1 it thins out too, so tiny test scenes stay tiny.
  const double detail = std::sqrt(std::min(scale_, 1.0));
  giant.leavesPerTip = std::max(8, int(std::lround(48 * detail)));
  giant.leafSegments = 2;
  giant.leafSize = 1.3f;
  giant.aerialRoots = std::max(16, int(std::lround(160 * detail)));
  giant.rootRings = 24;
  giant.rootSides = 8;
  giant.rootRadius = 0.1f;
  PlantDesign design = designTree(giant, streamKey(seed_, 0xba2));
  int32_t object =
      addPlantObject(plan_, "isIronwoodA1/ironwood", design, [mat = mat_](const PlantPart& part) {
        return part.role == PartRole::Leaves ? mat.giantLeaves : mat.giantBark;
      });
  const uint64_t count = scaledCount(4, scale_);
  ScatterRule rule;
  rule.scaleMin = 0.85f;
  rule.scaleMax = 1.1f;
  rule.tiltDegrees = 1;
  rule.sink = 0.3f;
  Region region;
  region.theta0 = 1.2f;
  region.theta1 = 2.3f;
  region.rho0 = 0.35f;
  region.rho1 = 0.82f;
  region.yMin = 1.5f;
  region.yMax = 60;
  auto others = std::make_shared<const Scatter>(rule, regionGround(shape_, region),
                                                streamKey(seed_, 0xba3), count);
  Vec2f hero = shape_->heroSpot;
  float heroY = shape_->surface(hero.x, hero.y);
  plan_.addInstances(object, count, [=](uint64_t i) {
    if (i > 0) return others->transform(i);
    return Affine3f::translate({hero.x, heroY - 0.3f, hero.y}) * Affine3f::rotate({0, 1, 0}, 0.7f);
  });
}

void IslandPlanner::addElementSpecies() {
  std::vector<ElementSpecies> table = islandSpecies();
  for (size_t k = 0; k < table.size(); ++k) {
    const ElementSpecies& e = table[k];
    const uint32_t designSeed = streamKey(seed_, 0x5bed, uint32_t(k));
    Species s;
    s.name = e.element + "/" + e.name;
    s.count = scaledCount(e.count, scale_);
    s.variants = std::max(1, int(std::lround(e.variants * variantFactor_)));
    s.design = [kind = e.kind, designSeed](int v) { return designPlant(kind, v, designSeed); };
    s.material = [mat = mat_, kind = e.kind](const PlantPart& part, int v) {
      return mat.forKind(kind, part.role, v);
    };
    s.rule = e.rule;
    s.ground = regionGround(shape_, e.region);
    addSpecies(plan_, s, streamKey(seed_, 0x5bec, uint32_t(k)));
  }
}

void IslandPlanner::addLightsAndViews() {
  // Below the horizon: the colour of the open sea, so the ocean's far edge does not show.
  addDaylight(plan_, {0.35f, 0.8f, 0.45f}, {0.16f, 0.34f, 0.8f}, {0.7f, 0.8f, 0.95f},
              {0.04f, 0.09f, 0.13f}, 0.05f);
  const IslandShape& shape = *shape_;
  auto surfaceAt = [&](Vec2f p) { return shape.surface(p.x, p.y); };
  Vec2f shore = shape.shoreCamera, beach = shape.beachCamera, campfire = shape.campfire;
  plan_.views.push_back(
      {.name = "default",
       .from = {shore.x, std::max(surfaceAt(shore), 0.0f) + 3.0f, shore.y},
       // Between the two peaks, so both are in the frame.
       .at = {lerpf(shape.peaks[0].centre.x, shape.peaks[1].centre.x, 0.35f), 0.4f * kPeakHeight,
              lerpf(shape.peaks[0].centre.y, shape.peaks[1].centre.y, 0.35f)},
       .fovY = 50});
  plan_.views.push_back({.name = "beach",
                         .from = {beach.x, surfaceAt(beach) + 1.3f, beach.y},
                         .at = {campfire.x, surfaceAt(campfire) + 0.6f, campfire.y},
                         .fovY = 55});
  // Steep enough that the horizon (and the ocean's edge) stays out of the frame.
  plan_.views.push_back({.name = "overview",
                         .from = {0.3f * kCoastRadius, 2.1f * kCoastRadius, 1.0f * kCoastRadius},
                         .at = {0, 0, 0.1f * kCoastRadius},
                         .fovY = 55});
}

}  // namespace

ScenePlan planIsland(double scale, uint32_t seed) {
  return IslandPlanner(scale, seed).plan();
}

}  // namespace ferry::builtin
