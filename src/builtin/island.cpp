#include "builtin/island.h"

#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>

#include "builtin/noise.h"
#include "builtin/plants.h"
#include "builtin/procedural_texture.h"
#include "builtin/terrain.h"
#include "builtin/vegetation.h"

namespace ferry::builtin {
namespace {

// Layout, in metres. The ocean's edges, the seabed and the mountain's apex
// are the scene's bounds; everything else is kept strictly inside them.
constexpr float kCoastRadius = 450;       // mean distance of the shoreline from the centre
constexpr float kCoastVariation = 0.16f;  // shoreline radius varies within +-16%
constexpr float kHillHeight = 48;
constexpr float kTerrainCap = 80;       // soft ceiling of the terrain itself
constexpr float kSeabed = -40;          // terrain floor and skirt: the scene's lowest point
constexpr float kMountainHeight = 280;  // the apex vertex: the scene's highest point
constexpr float kMountainBase = -25;    // the rim hides under the terrain or deep in the sea
constexpr float kMountainRadius = 0.6f * kCoastRadius;
constexpr float kVegetationLine = 140;  // nothing grows above (tallest plant < 40 m)
constexpr float kOceanHalfSize = 4 * kCoastRadius;
constexpr float kTerrainHalfSize = 1.45f * (1 + kCoastVariation) * kCoastRadius;
constexpr float kBeachTheta0 = 0.6f, kBeachTheta1 = 2.55f;  // the south shore, facing +z
constexpr float kBeachRho0 = 0.84f, kBeachRho1 = 1.05f;
constexpr float kNoHeight = -std::numeric_limits<float>::infinity();
constexpr Vec3f kDeepSeabed{0.06f, 0.1f, 0.1f};

float scaledResolution(float base, double scale, int lo, int hi) {
  double v = std::round(double(base) * std::sqrt(scale));
  return float(std::clamp(v, double(lo), double(hi)));
}

struct Cliff {
  Vec2f centre;
  float yaw = 0;
  RockParams rock;
  uint32_t seed = 0;
};

struct Spot {
  Vec2f at;
  float radius;
  bool groundCoverToo;  // also keeps grass, ferns and flowers away
};

// The island's ground as functions of (x, z): the heightfield the terrain
// mesh is made from, and the set pieces' surfaces, so plants can be put on
// whichever is on top without looking at any mesh.
class IslandShape {
 public:
  explicit IslandShape(uint32_t seed) : seed_(seed) {
    coastTable_.resize(kCoastSamples + 1);
    for (int i = 0; i <= kCoastSamples; ++i) {
      float theta = -kPi + 2 * kPi * float(i % kCoastSamples) / float(kCoastSamples);
      float n = fbm(1.5f * std::cos(theta) + 10, 1.5f * std::sin(theta) + 10, seed + 11, 4);
      coastTable_[i] = kCoastRadius * (1 + kCoastVariation * std::clamp(n, -1.0f, 1.0f));
    }
    mountainCentre = {-0.1f * kCoastRadius, -0.45f * kCoastRadius};
    secondSummit =
        mountainCentre + Vec2f{std::cos(0.3f), std::sin(0.3f)} * (0.4f * kMountainRadius);
    const float cliffAngles[3] = {3.6f, 5.3f, 0.15f};
    for (int k = 0; k < 3; ++k) {
      Cliff c;
      c.centre = polar(cliffAngles[k], 1.0f);
      c.yaw = -(cliffAngles[k] + kPi / 2);  // turns the long (x) axis along the shore
      c.rock.radii = {75, 34, 48};
      c.rock.roughness = 0.2f;
      c.rock.frequency = 1.3f;
      c.rock.octaves = 5;
      c.rock.sink = 0.85f;
      c.seed = streamKey(seed, 0xc11f, uint32_t(k));
      cliffs.push_back(c);
    }
    heroSpot = polar(1.5f, 0.82f);
    campfire = polar(1.75f, 0.925f);
    const float lanternAngles[4] = {1.67f, 1.70f, 1.73f, 1.76f};
    for (int k = 0; k < 4; ++k) lanterns[k] = polar(lanternAngles[k], 0.905f);
    beachCamera = polar(1.79f, 0.945f);
    shoreCamera = polar(1.62f, 1.04f);
    spots.push_back({heroSpot, 24, false});  // room for its crown
    spots.push_back({campfire, 7, true});
    for (Vec2f l : lanterns) spots.push_back({l, 1.5f, true});
    // A clearing from the beach camera to the campfire, so the view sees it.
    Vec2f sight = campfire - beachCamera;
    spots.push_back({beachCamera + sight * 0.5f,
                     0.5f * std::sqrt(sight.x * sight.x + sight.y * sight.y) + 3, true});
  }

  // The shoreline's distance from the centre in direction theta. Tabulated:
  // every height, colour and placement query needs it, and it is smooth.
  float coast(float theta) const {
    float turns = (theta + kPi) / (2 * kPi);
    float x = (turns - std::floor(turns)) * float(kCoastSamples);  // any angle, wrapped
    int i = std::clamp(int(x), 0, kCoastSamples - 1);
    return lerpf(coastTable_[i], coastTable_[i + 1], x - float(i));
  }
  Vec2f polar(float theta, float rho) const {
    float r = coast(theta) * rho;
    return {r * std::cos(theta), r * std::sin(theta)};
  }
  // Direction and normalized distance from the centre (1: on the shoreline).
  struct Where {
    float theta, rho;
  };
  Where where(float x, float z) const {
    float theta = std::atan2(z, x);
    return {theta, std::sqrt(x * x + z * z) / coast(theta)};
  }
  float rho(float x, float z) const { return where(x, z).rho; }

  // The shelf, shoreline dip and drop to the seabed, as a function of the
  // normalized distance from the centre (1: the shoreline).
  static float coastProfile(float rho) {
    float shelf = 2.6f * (1 - smoothstep(0.84f, 1.02f, rho));
    float dip = -0.8f * smoothstep(0.96f, 1.06f, rho);
    float drop = kSeabed * smoothstep(1.0f, 1.4f, rho);
    return shelf + dip + drop;
  }

  float terrain(float x, float z) const { return terrainAt(x, z, rho(x, z)); }
  float terrainAt(float x, float z, float r) const {
    float inland = smoothstep(0.93f, 0.2f, r);
    float hills = kHillHeight * std::pow(inland, 1.4f) *
                  (0.55f + 0.45f * fbm(x / 170, z / 170, seed_ + 21, 5));
    float detail = 2.0f * fbm(x / 30, z / 30, seed_ + 31, 3) * smoothstep(0.95f, 0.75f, r);
    float h = coastProfile(r) + hills + detail;
    // The floor stays just above the seabed plane, which it would otherwise
    // touch and flicker with.
    return h > 0 ? kTerrainCap * std::tanh(h / kTerrainCap) : std::max(h, kSeabed + 0.5f);
  }

  // Height of the mountain at a point within its footprint; u is the
  // normalized distance from its axis (0: apex), clamped to the footprint.
  float mountainAt(float x, float z, float u) const {
    u = std::clamp(u, 0.0f, 1.0f);
    // Ridges radiate from the summit: noise around the axis, bending slowly
    // with the distance from it.
    float angle = std::atan2(z - mountainCentre.y, x - mountainCentre.x);
    float n = fbm(4 * std::cos(angle) + 1.5f * u, 4 * std::sin(angle) + 1.5f * u, seed_ + 41, 4);
    float ridge = std::clamp(1 - std::abs(n), 0.0f, 1.0f);
    ridge *= ridge;
    float gullies = 3.0f * fbm(x / 15, z / 15, seed_ + 43, 3) * 4 * u * (1 - u);
    // A lower second summit on the shoulder towards +x.
    float dx = x - secondSummit.x, dz = z - secondSummit.y;
    float d2 = std::sqrt(dx * dx + dz * dz) / (0.45f * kMountainRadius);
    float second = 0.6f * std::pow(std::max(0.0f, 1 - d2), 2.0f);
    float profile = std::max(std::pow(1 - u, 2.2f), second);
    // Profile and multiplier are at most 1 and exactly 1 at the axis, and the
    // gullies vanish there: the apex is the top.
    return kMountainBase +
           (kMountainHeight - kMountainBase) * profile * (1 - 0.6f * u * (1 - ridge)) + gullies;
  }
  float mountain(float x, float z) const {
    float dx = x - mountainCentre.x, dz = z - mountainCentre.y;
    float u = std::sqrt(dx * dx + dz * dz) / kMountainRadius;
    return u < 1 ? mountainAt(x, z, u) : kNoHeight;
  }

  static float beachEdge(float theta, float rho) {
    return smoothstep(kBeachTheta0, kBeachTheta0 + 0.15f, theta) *
           smoothstep(kBeachTheta1, kBeachTheta1 - 0.15f, theta) *
           smoothstep(kBeachRho0, kBeachRho0 + 0.04f, rho);
  }
  // A smooth sand layer just above the shelf; it dives under the terrain at
  // its inner edge and ends, and under the sea at its outer edge.
  static float beachAt(float theta, float rho) {
    return coastProfile(rho) + 0.3f - 3.0f * (1 - beachEdge(theta, rho));
  }
  static float beachIn(Where w) {
    if (w.theta < kBeachTheta0 || w.theta > kBeachTheta1) return kNoHeight;
    if (w.rho < kBeachRho0 || w.rho > kBeachRho1) return kNoHeight;
    return beachAt(w.theta, w.rho);
  }

  // Whichever of the terrain and the set pieces is on top.
  float surface(float x, float z, Where w) const {
    return std::max(terrainAt(x, z, w.rho), std::max(mountain(x, z), beachIn(w)));
  }
  float surface(float x, float z) const { return surface(x, z, where(x, z)); }

  bool inCliff(Vec2f p, float margin) const {
    for (const Cliff& c : cliffs) {
      float dx = p.x - c.centre.x, dz = p.y - c.centre.y;
      float cs = std::cos(-c.yaw), sn = std::sin(-c.yaw);
      // Into the cliff's frame (inverse of its rotation about y).
      float lx = cs * dx + sn * dz, lz = -sn * dx + cs * dz;
      float ax = c.rock.radii.x * (1 + c.rock.roughness) + margin;
      float az = c.rock.radii.z * (1 + c.rock.roughness) + margin;
      if ((lx * lx) / (ax * ax) + (lz * lz) / (az * az) < 1) return true;
    }
    return false;
  }

  bool excluded(Vec2f p, bool groundCover) const {
    if (inCliff(p, 4)) return true;
    for (const Spot& s : spots) {
      if (groundCover && !s.groundCoverToo) continue;
      float dx = p.x - s.at.x, dz = p.y - s.at.y;
      if (dx * dx + dz * dz < s.radius * s.radius) return true;
    }
    return false;
  }

  Vec2f mountainCentre, secondSummit;
  std::vector<Cliff> cliffs;
  Vec2f heroSpot, campfire, beachCamera, shoreCamera;
  std::array<Vec2f, 4> lanterns;
  std::vector<Spot> spots;

 private:
  static constexpr int kCoastSamples = 4096;
  uint32_t seed_;
  std::vector<float> coastTable_;
};

using Shape = std::shared_ptr<const IslandShape>;

// Where a species may grow: a band of normalized distance from the centre
// and a band of heights.
Ground islandGround(const Shape& shape, float rho0, float rho1, float yMin, float yMax,
                    bool groundCover) {
  Ground g;
  g.sample = [shape, rho0, rho1](HashRng& rng) {
    float theta = rng.uniform(0, 2 * kPi);
    float rho = std::sqrt(lerpf(rho0 * rho0, rho1 * rho1, rng.uniform()));
    return shape->polar(theta, rho);
  };
  g.accept = [shape, rho0, rho1, yMin, yMax, groundCover](Vec2f p, float& y) {
    IslandShape::Where w = shape->where(p.x, p.y);
    if (w.rho < rho0 || w.rho > rho1) return false;
    if (shape->excluded(p, groundCover)) return false;
    y = shape->surface(p.x, p.y, w);
    return y >= yMin && y <= yMax;
  };
  g.normal = [shape](Vec2f p) {
    return heightNormal([&](float x, float z) { return shape->surface(x, z); }, p.x, p.y, 0.75f);
  };
  return g;
}

Vec3f groundColour(const IslandShape& shape, float x, float z, uint32_t seed) {
  const Vec3f sand{0.36f, 0.3f, 0.2f}, wetSand{0.2f, 0.17f, 0.11f}, deep = kDeepSeabed;
  const Vec3f grass{0.1f, 0.22f, 0.045f}, forestFloor{0.13f, 0.11f, 0.05f};
  const Vec3f rock{0.22f, 0.2f, 0.18f}, moss{0.08f, 0.16f, 0.05f};
  IslandShape::Where w = shape.where(x, z);
  float y = shape.surface(x, z, w);
  float r = w.rho;
  float n = fbm(x / 9, z / 9, seed + 51, 3);
  float coarse = fbm(x / 60, z / 60, seed + 53, 2);
  if (y < 0) return lerp(wetSand, deep, smoothstep(0.0f, 25.0f, -y)) * (0.9f + 0.1f * n);
  Vec3f green = lerp(grass, forestFloor, std::clamp(0.5f + 0.8f * coarse, 0.0f, 1.0f));
  Vec3f c = lerp(green, moss, smoothstep(80.0f, 150.0f, y));
  c = lerp(c, rock, smoothstep(150.0f, 200.0f, y + 20 * n));
  float sandiness = smoothstep(0.8f, 0.87f, r + 0.03f * n) * (1 - smoothstep(2.5f, 4.5f, y));
  c = lerp(c, lerp(sand, wetSand, smoothstep(0.6f, 0.1f, y)), sandiness);
  return c * (0.85f + 0.15f * n);
}

struct IslandTextures {
  int32_t terrain, rock, sand, bark, leaves, banyanLeaves, palmBark, palmFronds, fern, grass, petal;
};

// Roles to materials for the plants; some species override a role.
struct IslandMaterials {
  int32_t terrain, sand, rock, ocean, seabed, bark, leaves, palmBark, palmFronds, coconut, fern,
      grass, stem, flowerCentre, driftwood, banyanBark, banyanLeaves, lanternGlow, flame,
      lanternPole;
  std::array<int32_t, 3> petals;

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
};

// A flat square as wide as the ocean, at height y.
MeshRecipe oceanWideSquare(std::string name, int32_t material, float y) {
  MeshRecipe r;
  r.name = std::move(name);
  r.material = material;
  r.counts = {4, 2};
  r.hasUvs = false;
  r.build = [y] {
    MeshBuilder b(true, false, {4, 2});
    const float w = kOceanHalfSize;
    int32_t a = b.vertex({-w, y, -w}), c = b.vertex({-w, y, w}), d = b.vertex({w, y, w}),
            e = b.vertex({w, y, -w});
    b.quad(a, c, d, e);
    return b.finish();
  };
  return r;
}

// The random numbers that shape variant v of species `species`.
HashRng variantRng(uint32_t seed, uint32_t species, int v) {
  return HashRng(seed, 0xa7a, species, uint32_t(v));
}

// Makes the island's plan one step at a time, in a fixed order: the indices
// of textures, materials, meshes and objects, and the species' random
// streams, depend on it. Every recipe captures what it needs by value: the
// planner is gone when the plan is materialized.
class IslandPlanner {
 public:
  IslandPlanner(double scale, uint32_t seed)
      : scale_(scale),
        seed_(seed),
        variantFactor_(int(std::clamp(std::floor(std::sqrt(scale)), 1.0, 32.0))),
        shape_(std::make_shared<const IslandShape>(seed)) {
    plan_.name = "island";
    grid_.x0 = grid_.z0 = -kTerrainHalfSize;
    grid_.x1 = grid_.z1 = kTerrainHalfSize;
    grid_.segments = int(scaledResolution(1024, scale, 64, 16384));
    grid_.skirtY = kSeabed;
  }

  ScenePlan plan() && {
    addMaterials(addTextures());
    addTerrainMesh(plan_, "island-terrain", mat_.terrain, grid_,
                   [shape = shape_](float x, float z) { return shape->terrain(x, z); });
    addMountain();
    addSeaCliffs();
    addBeach();
    // The seabed beyond the terrain, out to the ocean's edge: without it the
    // sea would look different over the terrain than beyond it.
    plan_.addSingleInstanceMesh(oceanWideSquare("seabed", mat_.seabed, kSeabed));
    plan_.addSingleInstanceMesh(oceanWideSquare("ocean", mat_.ocean, 0));
    addCampfire();
    addLanterns();
    addHeroBanyan();
    addSpecies(
        plan_,
        {trees(), palms(), bushes(), ferns(), grass(), flowers(), rocks(), boulders(), driftwood()},
        streamKey(seed_, 0x5bec));
    addLightsAndViews();
    plan_.bounds.extend(Vec3f(-kOceanHalfSize, kSeabed, -kOceanHalfSize));
    plan_.bounds.extend(Vec3f(kOceanHalfSize, kMountainHeight, kOceanHalfSize));
    return std::move(plan_);
  }

 private:
  IslandTextures addTextures();
  void addMaterials(const IslandTextures& tex);
  void addMountain();
  void addSeaCliffs();
  void addBeach();
  void addCampfire();
  void addLanterns();
  void addHeroBanyan();
  Species trees() const;
  Species palms() const;
  Species bushes() const;
  Species ferns() const;
  Species grass() const;
  Species flowers() const;
  Species rocks() const;
  Species boulders() const;
  Species driftwood() const;
  void addLightsAndViews();

  const double scale_;
  const uint32_t seed_;
  const int variantFactor_;  // species have more variants in larger scenes
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
  t.banyanLeaves = texture("banyan-leaves", 512, 512, [=] {
    return leafClusterTexture("banyan-leaves", 512, seed + 5, {0.1f, 0.26f, 0.05f},
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
                      bool alphaCutout = false, float roughness = 0.9f) {
    return addDiffuseMaterial(plan_, name, colour, texture, alphaCutout, roughness);
  };
  IslandMaterials& mat = mat_;
  mat.terrain = material("island-ground", Vec3f(1), tex.terrain);
  mat.sand = material("beach-sand", Vec3f(1), tex.sand);
  mat.rock = material("rock", Vec3f(1), tex.rock, false, 0.8f);
  Material water;
  water.name = "ocean";
  water.baseColor = {0.9f, 0.97f, 1.0f};
  water.transmission = 1;
  water.ior = 1.33f;
  // Slightly rough: light reaches a diffuse seabed under a perfectly smooth
  // surface only by caustic paths, which a path tracer with light sampling
  // finds by chance (white speckles on black); a rough surface takes light
  // samples itself, so the sea reads as sky and sun reflected on dark water.
  water.roughness = 0.12f;
  mat.ocean = plan_.addMaterial(water);
  mat.seabed = material("seabed", kDeepSeabed);
  mat.bark = material("bark", Vec3f(1), tex.bark);
  mat.leaves = material("leaves", Vec3f(1), tex.leaves, true, 0.6f);
  mat.palmBark = material("palm-bark", Vec3f(1), tex.palmBark);
  mat.palmFronds = material("palm-fronds", Vec3f(1), tex.palmFronds, true, 0.6f);
  mat.coconut = material("coconut", {0.22f, 0.15f, 0.07f}, kNoTexture, false, 0.6f);
  mat.fern = material("fern", Vec3f(1), tex.fern, true, 0.7f);
  mat.grass = material("grass", Vec3f(1), tex.grass, false, 0.7f);
  mat.stem = material("flower-stem", {0.08f, 0.22f, 0.04f});
  mat.petals = {material("petal-red", {1.0f, 0.12f, 0.15f}, tex.petal, true, 0.6f),
                material("petal-yellow", {1.0f, 0.85f, 0.2f}, tex.petal, true, 0.6f),
                material("petal-white", {0.95f, 0.95f, 0.92f}, tex.petal, true, 0.6f)};
  mat.flowerCentre = material("flower-centre", {0.8f, 0.5f, 0.05f});
  mat.driftwood = material("driftwood", {0.9f, 0.88f, 0.85f}, tex.bark);
  mat.banyanBark = material("banyan-bark", {0.85f, 0.82f, 0.78f}, tex.bark);
  mat.banyanLeaves = material("banyan-leaves", Vec3f(1), tex.banyanLeaves, true, 0.6f);
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

void IslandPlanner::addMountain() {
  const Shape shape = shape_;
  const TerrainGrid grid = grid_;
  const int rings = int(scaledResolution(128, scale_, 12, 2048));
  const int segments = int(scaledResolution(512, scale_, 48, 8192));
  MeshRecipe r;
  r.name = "mountain";
  r.material = mat_.terrain;  // painted by the terrain texture, which knows the mountain
  r.counts = polarCapCounts(rings, segments);
  r.build = [shape, grid, rings, segments] {
    MeshBuilder b(true, true, polarCapCounts(rings, segments));
    const Vec2f c = shape->mountainCentre;
    addPolarCap(
        b, rings, segments,
        [&](float r, float phi) {
          float x = r == 0 ? c.x : c.x + r * kMountainRadius * std::cos(phi);
          float z = r == 0 ? c.y : c.y + r * kMountainRadius * std::sin(phi);
          return Vec3f(x, shape->mountainAt(x, z, r), z);
        },
        [&](Vec3f p) { return grid.uvAt(p.x, p.z); });
    Mesh m = b.finish();
    auto height = [&](float x, float z) {
      float dx = x - c.x, dz = z - c.y;
      return shape->mountainAt(x, z, std::sqrt(dx * dx + dz * dz) / kMountainRadius);
    };
    for (size_t v = 0; v < m.positions.size(); ++v)
      m.normals[v] = heightNormal(height, m.positions[v].x, m.positions[v].z, 0.5f);
    return m;
  };
  plan_.addSingleInstanceMesh(std::move(r));
}

void IslandPlanner::addSeaCliffs() {
  for (size_t k = 0; k < shape_->cliffs.size(); ++k) {
    const int detail = int(scaledResolution(48, scale_, 8, 1024));
    MeshRecipe r;
    r.name = fmt::format("sea-cliff-{}", k);
    r.material = mat_.rock;
    r.counts = cubeSphereCounts(detail);
    r.build = [shape = shape_, k, detail] {
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
    plan_.addSingleInstanceMesh(std::move(r));
  }
}

void IslandPlanner::addBeach() {
  const int nu = int(scaledResolution(480, scale_, 32, 8192));
  const int nv = int(scaledResolution(48, scale_, 6, 1024));
  const float arc = kCoastRadius * (kBeachTheta1 - kBeachTheta0);
  const float depth = kCoastRadius * (kBeachRho1 - kBeachRho0);
  MeshRecipe r;
  r.name = "beach";
  r.material = mat_.sand;
  r.counts = gridCounts(nu, nv);
  r.build = [shape = shape_, nu, nv, arc, depth] {
    MeshBuilder b(true, true, gridCounts(nu, nv));
    addGrid(b, nu, nv,
            [&](float u, float v) {
              float theta = lerpf(kBeachTheta0, kBeachTheta1, u);
              float rho = lerpf(kBeachRho0, kBeachRho1, v);
              Vec2f p = shape->polar(theta, rho);
              return Vec3f(p.x, IslandShape::beachAt(theta, rho), p.y);
            },
            {arc / 5, depth / 5});
    Mesh m = b.finish();
    computeVertexNormals(m);
    return m;
  };
  plan_.addSingleInstanceMesh(std::move(r));
}

void IslandPlanner::addCampfire() {
  const Vec2f at = shape_->campfire;
  const float y = shape_->surface(at.x, at.y);
  const uint32_t seed = seed_;
  MeshRecipe flame;
  flame.name = "campfire-flame";
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
  stones.name = "campfire-stones";
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
  int32_t o = plan_.addObject("campfire", {f, s});
  plan_.addInstances(o, 1, [](uint64_t) { return Affine3f::identity(); });
}

void IslandPlanner::addLanterns() {
  for (size_t k = 0; k < shape_->lanterns.size(); ++k) {
    const Vec2f at = shape_->lanterns[k];
    const float y = shape_->surface(at.x, at.y);
    MeshRecipe pole;
    pole.name = fmt::format("lantern-{}-pole", k);
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
    glow.name = fmt::format("lantern-{}-glow", k);
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
    int32_t o = plan_.addObject(fmt::format("lantern-{}", k), {p, g});
    plan_.addInstances(o, 1, [](uint64_t) { return Affine3f::identity(); });
  }
}

void IslandPlanner::addHeroBanyan() {
  TreeParams banyan;
  banyan.trunkLength = 9;
  banyan.trunkRadius = 1.4f;
  banyan.trunkRings = 40;
  banyan.trunkSides = 32;
  banyan.trunkTaper = 0.5f;
  banyan.trunkLean = 0.05f;
  banyan.trunkFlare = 0.8f;
  banyan.levels = {{12, 24, 16, 1.5f, 0.45f, 70, 0.55f, 0.05f, 0.35f},
                   {6, 12, 10, 0.5f, 0.5f, 45, 0.2f, 0.3f, 0.4f},
                   {5, 8, 6, 0.5f, 0.5f, 40, 0.3f, 0.2f, 0.4f},
                   {4, 5, 4, 0.5f, 0.5f, 40, 0.3f, 0.15f, 0.4f}};
  // Below scale 1 the banyan thins out too, so tiny test scenes stay tiny.
  const double heroDetail = std::sqrt(std::min(scale_, 1.0));
  banyan.leavesPerTip = std::max(8, int(std::lround(48 * heroDetail)));
  banyan.leafSegments = 2;
  banyan.leafSize = 1.3f;
  banyan.aerialRoots = std::max(16, int(std::lround(160 * heroDetail)));
  banyan.rootRings = 24;
  banyan.rootSides = 8;
  banyan.rootRadius = 0.1f;
  PlantDesign design = designTree(banyan, streamKey(seed_, 0xba2));
  int32_t object = addPlantObject(plan_, "banyan", design, [mat = mat_](PartRole role) {
    return role == PartRole::Leaves ? mat.banyanLeaves : mat.banyanBark;
  });
  const uint64_t count = uint64_t(std::clamp(std::floor(std::sqrt(scale_)), 1.0, 64.0));
  ScatterRule rule;
  rule.scaleMin = 0.85f;
  rule.scaleMax = 1.1f;
  rule.tiltDegrees = 1;
  rule.sink = 0.3f;
  // The first banyan stands where the default view sees it; more of them
  // (at larger scales) go anywhere in the lowlands.
  auto others = std::make_shared<const Scatter>(
      rule, islandGround(shape_, 0.3f, 0.8f, 1.5f, 60, false), streamKey(seed_, 0xba3), count);
  Vec2f hero = shape_->heroSpot;
  float heroY = shape_->surface(hero.x, hero.y);
  plan_.addInstances(object, count, [=](uint64_t i) {
    if (i > 0) return others->transform(i);
    return Affine3f::translate({hero.x, heroY - 0.3f, hero.y}) * Affine3f::rotate({0, 1, 0}, 0.7f);
  });
}

Species IslandPlanner::trees() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "tree";
  s.count = scaledCount(3000, scale_);
  s.variants = 3 * variantFactor_;
  s.design = [seed](int v) {
    HashRng rng = variantRng(seed, 1, v);
    TreeParams p;
    p.trunkLength = rng.uniform(6, 9);
    p.trunkRadius = rng.uniform(0.22f, 0.32f);
    p.trunkRings = 18;
    p.trunkSides = 12;
    p.trunkLean = rng.uniform(0.05f, 0.2f);
    p.levels = {{6 + v % 2, 10, 8, 0.6f, 0.55f, 50, 0.45f, 0.25f, 0.4f},
                {4, 6, 6, 0.5f, 0.55f, 45, 0.3f, 0.15f, 0.4f},
                {4, 4, 4, 0.45f, 0.55f, 40, 0.3f, 0.1f, 0.4f}};
    p.leavesPerTip = 48;
    p.leafSegments = 2;
    p.leafSize = 1.1f;
    return designTree(p, streamKey(seed, 0x7ee, uint32_t(v)));
  };
  s.material = [mat = mat_](PartRole r, int) { return mat.forPlantPart(r); };
  s.rule = {40, 60, 0.75f, 1.25f, 4, 0, 0.1f, 12};
  s.ground = islandGround(shape_, 0.12f, 0.86f, 1.5f, kVegetationLine, false);
  return s;
}

Species IslandPlanner::palms() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "palm";
  s.count = scaledCount(600, scale_);
  s.variants = 3 * variantFactor_;
  s.design = [seed](int v) {
    HashRng rng = variantRng(seed, 2, v);
    PalmParams p;
    p.height = rng.uniform(7, 12);
    p.lean = rng.uniform(0.1f, 0.35f);
    p.fronds = 14 + v % 4;
    p.coconuts = 4 + v % 4;
    return designPalm(p, streamKey(seed, 0xba1, uint32_t(v)));
  };
  s.material = [mat = mat_](PartRole r, int) {
    return r == PartRole::Wood ? mat.palmBark : mat.forPlantPart(r);
  };
  s.rule = {0, 0, 0.8f, 1.2f, 3, 0, 0.1f, 12};
  s.ground = islandGround(shape_, 0.86f, 0.97f, 0.3f, 8, false);
  return s;
}

Species IslandPlanner::bushes() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "bush";
  s.count = scaledCount(6000, scale_);
  s.variants = 2 * variantFactor_;
  s.design = [seed](int v) {
    HashRng rng = variantRng(seed, 3, v);
    TreeParams p;
    p.trunkLength = rng.uniform(0.4f, 0.7f);
    p.trunkRadius = 0.06f;
    p.trunkRings = 4;
    p.trunkSides = 6;
    p.trunkFlare = 0.3f;
    p.levels = {{5, 6, 5, 2.2f, 0.8f, 40, 0.2f, 0.3f, 0.4f},
                {4, 4, 4, 0.5f, 0.6f, 40, 0.3f, 0.1f, 0.4f}};
    p.leavesPerTip = 40 + 4 * (v % 3);
    p.leafSegments = 2;
    p.leafSize = 0.35f;
    return designTree(p, streamKey(seed, 0xb05, uint32_t(v)));
  };
  s.material = [mat = mat_](PartRole r, int) { return mat.forPlantPart(r); };
  s.rule = {25, 25, 0.6f, 1.3f, 6, 0.3f, 0.05f, 12};
  s.ground = islandGround(shape_, 0.2f, 0.9f, 1, kVegetationLine, false);
  return s;
}

Species IslandPlanner::ferns() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "fern";
  s.count = scaledCount(6000, scale_);
  s.variants = 2 * variantFactor_;
  s.design = [seed](int v) {
    FernParams p;
    p.fronds = 18 + 2 * (v % 3);
    p.length = 1.0f + 0.1f * float(v % 3);
    return designFern(p, streamKey(seed, 0xfe2, uint32_t(v)));
  };
  s.material = [fern = mat_.fern](PartRole, int) { return fern; };
  s.rule = {40, 14, 0.6f, 1.4f, 8, 0.5f, 0.03f, 12};
  s.ground = islandGround(shape_, 0.15f, 0.85f, 2, kVegetationLine, true);
  return s;
}

Species IslandPlanner::grass() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "grass";
  s.count = scaledCount(45000, scale_);
  s.variants = 3 * variantFactor_;
  s.design = [seed](int v) {
    GrassParams p;
    p.blades = 128 + 16 * (v % 3);
    p.height = 0.5f + 0.1f * float(v % 3);
    return designGrass(p, streamKey(seed, 0x9a5, uint32_t(v)));
  };
  s.material = [grass = mat_.grass](PartRole, int) { return grass; };
  s.rule = {300, 26, 0.6f, 1.5f, 6, 0.7f, 0.02f, 12};
  s.ground = islandGround(shape_, 0.3f, 0.93f, 0.8f, kVegetationLine, true);
  return s;
}

Species IslandPlanner::flowers() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "flower";
  s.count = scaledCount(9000, scale_);
  s.variants = 3 * variantFactor_;
  s.design = [seed](int v) {
    FlowerParams p;
    p.stems = 12 + (v % 3);
    p.petals = 5 + (v % 2);
    return designFlowers(p, streamKey(seed, 0xf10, uint32_t(v)));
  };
  s.material = [mat = mat_](PartRole r, int v) {
    return r == PartRole::Petals ? mat.petals[size_t(v) % 3] : mat.forPlantPart(r);
  };
  s.rule = {60, 7, 0.7f, 1.3f, 5, 0.6f, 0.02f, 12};
  s.ground = islandGround(shape_, 0.3f, 0.9f, 1, kVegetationLine, true);
  return s;
}

Species IslandPlanner::rocks() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "rock";
  s.count = scaledCount(1500, scale_);
  s.variants = 4 * variantFactor_;
  s.design = [seed](int v) {
    HashRng rng = variantRng(seed, 7, v);
    RockParams p;
    p.detail = 16;
    p.radii = {rng.uniform(0.6f, 0.9f), rng.uniform(0.35f, 0.6f), rng.uniform(0.5f, 0.8f)};
    p.roughness = rng.uniform(0.2f, 0.35f);
    return designRock(p, streamKey(seed, 0x20c, uint32_t(v)));
  };
  s.material = [rock = mat_.rock](PartRole, int) { return rock; };
  s.rule = {0, 0, 0.3f, 1.6f, 30, 0.8f, 0.1f, 12};
  s.ground = islandGround(shape_, 0.0f, 1.02f, -3, kVegetationLine, false);
  return s;
}

Species IslandPlanner::boulders() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "boulder";
  s.count = scaledCount(60, scale_);
  s.variants = 2 * variantFactor_;
  s.design = [seed](int v) {
    HashRng rng = variantRng(seed, 8, v);
    RockParams p;
    p.detail = 32;
    p.radii = {rng.uniform(2.2f, 2.8f), rng.uniform(1.5f, 2.0f), rng.uniform(1.9f, 2.4f)};
    p.roughness = 0.3f;
    return designRock(p, streamKey(seed, 0xb01, uint32_t(v)));
  };
  s.material = [rock = mat_.rock](PartRole, int) { return rock; };
  s.rule = {0, 0, 0.7f, 1.4f, 15, 0.5f, 0.3f, 12};
  s.ground = islandGround(shape_, 0.92f, 1.06f, -4, 10, false);
  return s;
}

Species IslandPlanner::driftwood() const {
  const uint32_t seed = seed_;
  Species s;
  s.name = "driftwood";
  s.count = scaledCount(80, scale_);
  s.variants = 2 * variantFactor_;
  s.design = [seed](int v) {
    HashRng rng = variantRng(seed, 9, v);
    LogParams p;
    p.length = rng.uniform(2.0f, 4.0f);
    p.radius = rng.uniform(0.1f, 0.2f);
    return designLog(p, streamKey(seed, 0x109, uint32_t(v)));
  };
  s.material = [wood = mat_.driftwood](PartRole, int) { return wood; };
  s.rule = {0, 0, 0.7f, 1.3f, 4, 1.0f, 0.05f, 12};
  s.ground = islandGround(shape_, 0.9f, 0.99f, 0.1f, 3, false);
  return s;
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
       .at = {shape.mountainCentre.x, 0.4f * kMountainHeight, shape.mountainCentre.y},
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
