// The island's ground as functions of (x, z): the heightfield the ground
// tiles are made from, the two volcanic peaks, the beach's sand layer and the
// lava cliffs, so plants can be put on whichever is on top without looking at
// any mesh. Also the regions the island's elements occupy (docs/scenes.md):
// each element's ground and plants stay in its own region.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "builtin/plants.h"
#include "builtin/vegetation.h"
#include "core/math.h"

namespace ferry::builtin {

// Layout, in metres. The ocean's edges, the seabed and peak A's apex are the
// scene's bounds; everything else is kept strictly inside them.
constexpr float kCoastRadius = 450;       // mean distance of the shoreline from the centre
constexpr float kCoastVariation = 0.16f;  // shoreline radius varies within +-16%
constexpr float kSeabed = -40;            // the seabed plane: the scene's lowest point
constexpr float kPeakHeight = 280;        // peak A's apex vertex: the scene's highest point
constexpr float kVegetationLine = 140;    // nothing grows above (tallest plant < 40 m)
constexpr float kOceanHalfSize = 4 * kCoastRadius;
constexpr float kGroundHalfSize = 1.45f * (1 + kCoastVariation) * kCoastRadius;
constexpr float kBeachTheta0 = 0.6f, kBeachTheta1 = 2.55f;  // the south shore, facing +z
constexpr float kBeachRho0 = 0.84f, kBeachRho1 = 1.05f;
constexpr float kNoHeight = -std::numeric_limits<float>::infinity();
constexpr Vec3f kDeepSeabed{0.06f, 0.1f, 0.1f};  // the seabed's colour, and the deep ground's

// A volcanic cone with ridges; its apex (at r = 0) is its highest point.
struct Peak {
  Vec2f centre;
  float radius = 0;
  float height = 0;
  float base = -25;  // the rim hides under the ground or deep in the sea
  uint32_t seed = 0;
};

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

// Where an element's plants grow. Band: a sector of directions [theta0,
// theta1] (radians, any turn) and of normalized distances from the centre
// [rho0, rho1] (1: the shoreline). OnPeak: the slopes of peak `peak` between
// rho0 and rho1 of its radius. NearCliffs: within 40 m of the lava cliffs.
// Each only at heights in [yMin, yMax].
struct Region {
  enum class Kind { Band, OnPeak, NearCliffs } kind = Kind::Band;
  float theta0 = 0, theta1 = 2 * kPi;
  float rho0 = 0, rho1 = 1;
  float yMin = 0, yMax = kVegetationLine;
  int peak = 0;
  bool groundCover = false;  // kept away from the campfire's and lanterns' clearings too
};

class IslandShape {
 public:
  explicit IslandShape(uint32_t seed);

  // The shoreline's distance from the centre in direction theta (tabulated).
  float coast(float theta) const;
  Vec2f polar(float theta, float rho) const;
  struct Where {
    float theta, rho;
  };
  Where where(float x, float z) const;

  // The shelf, shoreline dip and drop to the seabed, by normalized distance.
  static float coastProfile(float rho);
  float ground(float x, float z) const;  // the heightfield of the ground tiles
  float groundAt(float x, float z, float rho) const;
  // Height of peak k at a point; u is the normalized distance from its axis.
  float peakAt(int k, float x, float z, float u) const;
  float peak(int k, float x, float z) const;  // kNoHeight outside its footprint
  static float beachAt(float theta, float rho);
  static float beachIn(Where w);

  // Whichever of the ground, the peaks and the beach is on top.
  float surface(float x, float z, Where w) const;
  float surface(float x, float z) const;

  bool inCliff(Vec2f p, float margin) const;
  bool excluded(Vec2f p, bool groundCover) const;
  bool inRegion(const Region& r, Vec2f p, Where w) const;

  std::array<Peak, 2> peaks;
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

// Where plants of a region may stand, and the ground's normal there.
Ground regionGround(const Shape& shape, const Region& region);

// The colour of the island's ground at (x, z), for its texture.
Vec3f groundColour(const IslandShape& shape, float x, float z, uint32_t seed);

}  // namespace ferry::builtin
