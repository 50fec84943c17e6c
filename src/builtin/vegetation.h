// Populating a terrain with plants: a species is a few variant objects and a
// scatter rule; instance i of a species is placed by a pure function of
// (seed, species, i). Counts are fixed by the plan (never by how many random
// candidates happen to be accepted), so the number of instances is known
// without placing any of them.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "builtin/noise.h"
#include "builtin/plants.h"
#include "builtin/scene_plan.h"

namespace ferry::builtin {

// Where a species may stand: `sample` proposes a spot (x, z) from its region,
// `accept` says whether the spot is allowed and gives the ground height.
struct Ground {
  std::function<Vec2f(HashRng&)> sample;
  std::function<bool(Vec2f, float&)> accept;
  std::function<Vec3f(Vec2f)> normal;  // unit ground normal, for slope alignment
};

struct ScatterRule {
  int clusterSize = 0;  // 0: spread over the region; else instances per cluster
  float clusterRadius = 10;
  float scaleMin = 0.8f, scaleMax = 1.2f;
  float tiltDegrees = 4;  // random lean
  float slopeAlign = 0;   // 0: upright, 1: follows the ground normal
  float sink = 0.05f;     // metres (before scaling) below the ground
  int attempts = 12;      // candidates tried before falling back
};

// Places instances of one species. A spot is tried `attempts` times; if none
// is accepted the instance falls back to its cluster centre, or to an anchor
// found once per species, so every instance lands on allowed ground.
class Scatter {
 public:
  Scatter(ScatterRule rule, Ground ground, uint32_t key, uint64_t count);

  Affine3f transform(uint64_t i) const;
  uint64_t clusterCount() const { return clusters_; }
  // A spot and its ground height; pure function of (key, c).
  Vec2f clusterCentre(uint64_t c, float& y) const;

 private:
  bool tryCandidates(HashRng& rng, const std::function<Vec2f(HashRng&)>& propose, Vec2f& spot,
                     float& y) const;

  ScatterRule rule_;
  Ground ground_;
  uint32_t key_;
  uint64_t clusters_ = 0;
  Vec2f anchor_;
  float anchorY_ = 0;
};

struct Species {
  std::string name;
  uint64_t count = 0;  // instances over all variants (at least one per variant)
  int variants = 1;
  std::function<PlantDesign(int variant)> design;
  std::function<int32_t(const PlantPart&, int variant)> material;
  ScatterRule rule;
  Ground ground;
};

// Adds one object per variant, named "<species>/<variant>", and the batches
// placing `count` instances among them. Returns the objects.
std::vector<int32_t> addSpecies(ScenePlan& plan, const Species& species, uint32_t key);

// Adds one object made of the design's parts.
int32_t addPlantObject(ScenePlan& plan, const std::string& name, const PlantDesign& design,
                       const std::function<int32_t(const PlantPart&)>& material);

// Adds the species in order, species k with key streamKey(key, k).
void addSpecies(ScenePlan& plan, const std::vector<Species>& species, uint32_t key);

// An instance count that grows in proportion to the scene's scale, at least 1.
uint64_t scaledCount(double base, double scale);

// Instances per variant when `count` instances are shared by `variants` objects.
uint64_t variantShare(uint64_t count, uint64_t variants, uint64_t variant);

}  // namespace ferry::builtin
