#include "builtin/island_elements.h"

#include "builtin/noise.h"

namespace ferry::builtin {
namespace {

Region band(float theta0, float theta1, float rho0, float rho1, float yMin = 0.8f,
            float yMax = kVegetationLine, bool groundCover = false) {
  Region r;
  r.theta0 = theta0;
  r.theta1 = theta1;
  r.rho0 = rho0;
  r.rho1 = rho1;
  r.yMin = yMin;
  r.yMax = yMax;
  r.groundCover = groundCover;
  return r;
}

Region onPeak(int peak, float u0, float u1, bool groundCover = false) {
  Region r;
  r.kind = Region::Kind::OnPeak;
  r.peak = peak;
  r.rho0 = u0;
  r.rho1 = u1;
  r.yMin = 1.5f;
  r.groundCover = groundCover;
  return r;
}

Region nearCliffs(float yMin, float yMax) {
  Region r;
  r.kind = Region::Kind::NearCliffs;
  r.yMin = yMin;
  r.yMax = yMax;
  return r;
}

constexpr float kAround = 2 * kPi;
// ScatterRule: cluster size and radius, scale range, tilt, slope alignment, sink, attempts.
constexpr ScatterRule kTreeRule{40, 60, 0.75f, 1.25f, 4, 0, 0.1f, 12};
constexpr ScatterRule kPalmRule{0, 0, 0.8f, 1.2f, 3, 0, 0.1f, 12};
constexpr ScatterRule kBushRule{25, 25, 0.6f, 1.3f, 6, 0.3f, 0.05f, 12};
constexpr ScatterRule kFernRule{40, 14, 0.6f, 1.4f, 8, 0.5f, 0.03f, 12};
constexpr ScatterRule kGrassRule{300, 26, 0.6f, 1.5f, 6, 0.7f, 0.02f, 12};
constexpr ScatterRule kFlowerRule{60, 7, 0.7f, 1.3f, 5, 0.6f, 0.02f, 12};
constexpr ScatterRule kPebbleRule{200, 12, 0.08f, 0.25f, 30, 0.9f, 0.01f, 12};
constexpr ScatterRule kRockRule{0, 0, 0.3f, 1.6f, 30, 0.8f, 0.1f, 12};
constexpr ScatterRule kStoneRule{50, 10, 0.15f, 0.45f, 30, 0.9f, 0.05f, 12};
constexpr ScatterRule kBoulderRule{0, 0, 0.7f, 1.4f, 15, 0.5f, 0.3f, 12};
constexpr ScatterRule kDebrisRule{0, 0, 0.5f, 1.2f, 4, 1.0f, 0.05f, 12};
constexpr ScatterRule kCoralRule{80, 15, 0.6f, 1.6f, 10, 0.8f, 0.05f, 12};

}  // namespace

std::vector<ElementSpecies> islandSpecies() {
  using K = PlantKind;
  const float beach0 = kBeachTheta0, beach1 = kBeachTheta1;
  return {
      // Terrain elements, with the species (and the number of variants of
      // each) that Disney's element files instance over them.
      {"isMountainA", "breadfruit", K::Breadfruit, 300, 1, onPeak(0, 0.15f, 0.95f), kTreeRule},
      {"isMountainA", "palm", K::Palm, 150, 16, onPeak(0, 0.3f, 0.95f), kPalmRule},
      {"isMountainA", "canopy", K::Canopy, 400, 1, onPeak(0, 0.1f, 0.9f), kTreeRule},
      {"isMountainA", "lowgrowth", K::Grass, 1500, 2, onPeak(0, 0.1f, 0.95f, true), kGrassRule},
      {"isMountainB", "breadfruit", K::Breadfruit, 200, 1, onPeak(1, 0.1f, 0.95f), kTreeRule},
      {"isMountainB", "palm", K::Palm, 100, 12, onPeak(1, 0.3f, 0.95f), kPalmRule},
      {"isMountainB", "fern", K::Fern, 1500, 14, onPeak(1, 0.1f, 0.95f, true), kFernRule},
      {"isMountainB", "canopy", K::Canopy, 300, 4, onPeak(1, 0.1f, 0.9f), kTreeRule},
      {"isDunesA", "palmdebris", K::Debris, 3000, 4, band(2.2f, 4.2f, 0.25f, 0.82f), kDebrisRule},
      {"isDunesA", "muskfern", K::Fern, 14000, 13, band(2.2f, 4.2f, 0.25f, 0.82f, 1, 140, true),
       kFernRule},
      {"isDunesA", "hibiscusflower", K::Flowers, 10000, 7,
       band(2.2f, 4.2f, 0.25f, 0.82f, 1, 140, true), kFlowerRule},
      {"isDunesB", "pandanus", K::Pandanus, 200, 1, band(-1.0f, 1.2f, 0.25f, 0.82f, 0.5f, 60),
       kPalmRule},
      {"isDunesB", "roots", K::Debris, 6000, 14, band(-1.0f, 1.2f, 0.25f, 0.82f), kDebrisRule},
      {"isDunesB", "ironwood", K::Broadleaf, 400, 2, band(-1.0f, 1.2f, 0.25f, 0.82f), kTreeRule},
      {"isBeach", "pebble", K::Pebble, 8000, 14, band(beach0, beach1, 0.86f, 1.03f, -1, 3, true),
       kPebbleRule},
      {"isBeach", "groundcover", K::Pebble, 6000, 22,
       band(beach0, beach1, 0.86f, 1.0f, -1, 3, true), kPebbleRule},
      {"isBeach", "stone", K::Stone, 3000, 6, band(beach0, beach1, 0.9f, 1.04f, -1.5f, 3),
       kStoneRule},
      {"isBeach", "shell", K::Shell, 6000, 14, band(beach0, beach1, 0.88f, 1.03f, -1, 3, true),
       kPebbleRule},
      {"isBeach", "palmdebris", K::Debris, 1500, 4, band(beach0, beach1, 0.86f, 0.99f, 0.1f, 3),
       kDebrisRule},
      {"isBeach", "seaweed", K::Seaweed, 4000, 5,
       band(beach0, beach1, 0.95f, 1.04f, -1.5f, 1, true), kGrassRule},
      {"isBeach", "hibiscusflower", K::Flowers, 1000, 4,
       band(beach0, beach1, 0.85f, 0.9f, 0.3f, 4, true), kFlowerRule},
      {"isCoastline", "palmdebris", K::Debris, 4000, 4,
       band(beach1, beach0 + kAround, 0.8f, 1.0f, -1, 6), kDebrisRule},
      {"isLavaRocks", "lavarock", K::Rock, 3000, 4, nearCliffs(-3, 40), kRockRule},
      {"isLavaRocks", "boulder", K::Boulder, 150, 2, nearCliffs(-4, 20), kBoulderRule},
      {"isCoral", "antler", K::AntlerCoral, 10000, 8, band(0, kAround, 1.1f, 1.3f, -16, -1.5f),
       kCoralRule},
      {"isCoral", "cabbage", K::CabbageCoral, 8000, 8, band(0, kAround, 1.1f, 1.3f, -16, -1.5f),
       kCoralRule},
      {"isCoral", "staghorn", K::AntlerCoral, 6000, 9, band(0, kAround, 1.1f, 1.3f, -16, -1.5f),
       kCoralRule},
      // Plant elements: the element's own plant (one design, as the
      // original's one base mesh per element), copied over its region, and
      // what the original instances over it.
      {"isIronwoodA1", "seedpod", K::Pebble, 3000, 1, band(1.2f, 2.3f, 0.35f, 0.82f, 1, 60, true),
       kPebbleRule},
      {"isIronwoodB", "ironwood", K::Broadleaf, 250, 1, band(-0.6f, 0.6f, 0.3f, 0.8f), kTreeRule},
      {"isBayCedarA1", "baycedar", K::Broadleaf, 200, 1, band(2.55f, 3.5f, 0.76f, 0.92f),
       kTreeRule},
      {"isPalmRig", "palm", K::Palm, 500, 1, band(0, kAround, 0.86f, 0.97f, 0.3f, 8), kPalmRule},
      {"isPalmDead", "palm", K::DeadPalm, 60, 1, band(3.5f, 4.6f, 0.84f, 0.95f, 0.3f, 8),
       kPalmRule},
      {"isPandanusA", "pandanus", K::Pandanus, 300, 1, band(-0.8f, 0.6f, 0.75f, 0.9f, 0.5f, 20),
       kPalmRule},
      {"isHibiscus", "hibiscus", K::Bush, 1500, 1, band(2.3f, 3.4f, 0.4f, 0.8f), kBushRule},
      {"isHibiscus", "flower", K::Flowers, 6000, 1, band(2.3f, 3.4f, 0.4f, 0.8f, 1, 140, true),
       kFlowerRule},
      {"isHibiscusYoung", "hibiscus", K::YoungBush, 2000, 1, band(3.4f, 4.4f, 0.35f, 0.8f),
       kBushRule},
      {"isGardeniaA", "gardenia", K::Bush, 1200, 1, band(0.6f, 1.5f, 0.4f, 0.8f), kBushRule},
      {"isGardeniaA", "flower", K::Flowers, 4000, 1, band(0.6f, 1.5f, 0.4f, 0.8f, 1, 140, true),
       kFlowerRule},
      {"isKava", "kava", K::Bush, 3000, 1, band(1.3f, 2.3f, 0.3f, 0.75f), kBushRule},
      {"isNaupakaA", "naupaka", K::Bush, 5000, 1, band(beach0, beach1, 0.8f, 0.87f, 0.5f, 10),
       kBushRule},
  };
}

PlantDesign designPlant(PlantKind kind, int v, uint32_t seed) {
  HashRng rng(seed, 0xa7a, uint32_t(kind), uint32_t(v));
  const uint32_t key = streamKey(seed, 0xd5, uint32_t(kind), uint32_t(v));
  switch (kind) {
    case PlantKind::Broadleaf:
    case PlantKind::Breadfruit:
    case PlantKind::Canopy: {
      TreeParams p;
      p.trunkLength = rng.uniform(6, 9);
      p.trunkRadius = rng.uniform(0.22f, 0.32f);
      p.trunkRings = 18;
      p.trunkSides = 12;
      p.trunkLean = rng.uniform(0.05f, 0.2f);
      p.levels = {{6 + v % 2, 10, 8, 0.6f, 0.55f, 50, 0.45f, 0.25f, 0.4f},
                  {4, 6, 6, 0.5f, 0.55f, 45, 0.3f, 0.15f, 0.4f},
                  {4, 4, 4, 0.45f, 0.55f, 40, 0.3f, 0.1f, 0.4f}};
      p.leavesPerTip = 96;
      p.leafSize = 0.8f;
      // The mountains' trees are the original's low-detail ones ("...Baked",
      // "canopyOnly_lo"): fewer, larger leaf cards.
      if (kind == PlantKind::Breadfruit) {
        p.leavesPerTip = 48;
        p.leafSize = 1.1f;
      } else if (kind == PlantKind::Canopy) {
        p.leavesPerTip = 16;
        p.leafSize = 1.8f;
      }
      return designTree(p, key);
    }
    case PlantKind::Palm:
    case PlantKind::DeadPalm:
    case PlantKind::Pandanus: {
      PalmParams p;
      p.height = rng.uniform(7, 12);
      p.lean = rng.uniform(0.1f, 0.35f);
      p.fronds = 14 + v % 4;
      p.coconuts = 4 + v % 4;
      if (kind == PlantKind::DeadPalm) {  // a few drooping, withered fronds
        p.fronds = 5 + v % 3;
        p.frondLength = 2.6f;
        p.coconuts = 0;
      } else if (kind == PlantKind::Pandanus) {  // short, with many narrow leaves
        p.height = rng.uniform(4, 6);
        p.trunkRadius = 0.12f;
        p.fronds = 28 + 2 * (v % 3);
        p.frondLength = 2.0f;
        p.frondWidth = 0.35f;
        p.frondSegments = 10;
        p.coconuts = 3;
      }
      return designPalm(p, key);
    }
    case PlantKind::Bush:
    case PlantKind::YoungBush: {
      TreeParams p;
      p.trunkLength = rng.uniform(0.4f, 0.7f);
      p.trunkRadius = 0.06f;
      p.trunkRings = 4;
      p.trunkSides = 6;
      p.trunkFlare = 0.3f;
      p.levels = {{5, 6, 5, 2.2f, 0.8f, 40, 0.2f, 0.3f, 0.4f},
                  {4, 4, 4, 0.5f, 0.6f, 40, 0.3f, 0.1f, 0.4f}};
      p.leavesPerTip = 40 + 4 * (v % 3);
      p.leafSize = 0.35f;
      if (kind == PlantKind::YoungBush) {
        p.levels[0].children = 3;
        p.leavesPerTip = 24;
      }
      return designTree(p, key);
    }
    case PlantKind::Fern: {
      FernParams p;  // about Disney's musk fern archives' size (docs/scenes.md)
      p.fronds = 26 + 2 * (v % 3);
      p.segments = 64;
      p.length = 1.0f + 0.1f * float(v % 3);
      return designFern(p, key);
    }
    case PlantKind::Grass:
    case PlantKind::Seaweed: {
      GrassParams p;
      p.blades = 128 + 16 * (v % 3);
      p.height = 0.5f + 0.1f * float(v % 3);
      if (kind == PlantKind::Seaweed) {  // low, sparse strands washed up on the sand
        p.blades = 200;
        p.height = 0.12f;
        p.radius = 0.4f;
        p.width = 0.03f;
      }
      return designGrass(p, key);
    }
    case PlantKind::Flowers: {
      FlowerParams p;  // about Disney's hibiscus flower archives' size
      p.stems = 46 + (v % 3);
      p.centreDetail = 3;
      p.petals = 5 + (v % 2);
      return designFlowers(p, key);
    }
    case PlantKind::Pebble:
    case PlantKind::Shell:
    case PlantKind::Stone:
    case PlantKind::Rock:
    case PlantKind::Boulder:
    case PlantKind::CabbageCoral: {
      RockParams p;
      p.detail = 16;
      p.radii = {rng.uniform(0.6f, 0.9f), rng.uniform(0.35f, 0.6f), rng.uniform(0.5f, 0.8f)};
      p.roughness = rng.uniform(0.2f, 0.35f);
      if (kind == PlantKind::Pebble) p.detail = 6;
      if (kind == PlantKind::Stone) p.detail = 8;
      if (kind == PlantKind::Shell) {
        p.detail = 6;
        p.radii = {0.6f, 0.12f, 0.45f};
        p.roughness = 0.1f;
      }
      if (kind == PlantKind::Boulder) {
        p.detail = 32;
        p.radii = {rng.uniform(2.2f, 2.8f), rng.uniform(1.5f, 2.0f), rng.uniform(1.9f, 2.4f)};
        p.roughness = 0.3f;
      }
      if (kind == PlantKind::CabbageCoral) {  // a lumpy, folded head
        p.detail = 10;
        p.radii = {0.8f, 0.5f, 0.8f};
        p.roughness = 0.45f;
        p.frequency = 3.0f;
      }
      return designRock(p, key);
    }
    case PlantKind::Debris: {
      LogParams p;
      p.length = rng.uniform(1.0f, 2.5f);
      p.radius = rng.uniform(0.04f, 0.08f);
      p.rings = 16;
      p.sides = 6;
      p.stubs = 2;
      return designLog(p, key);
    }
    case PlantKind::AntlerCoral: {  // branching, leafless
      TreeParams p;
      p.trunkLength = 0.3f;
      p.trunkRadius = 0.06f;
      p.trunkRings = 3;
      p.trunkSides = 6;
      p.trunkFlare = 0.2f;
      p.levels = {{5, 4, 5, 1.6f, 0.6f, 45, 0.3f, 0.4f, 0.5f},
                  {3, 3, 4, 0.6f, 0.6f, 35, 0.5f, 0.3f, 0.5f}};
      p.leavesPerTip = 0;
      return designTree(p, key);
    }
  }
  return {};
}

}  // namespace ferry::builtin
