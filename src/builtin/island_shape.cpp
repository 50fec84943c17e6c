#include "builtin/island_shape.h"

#include <algorithm>
#include <cmath>

#include "builtin/noise.h"
#include "builtin/terrain.h"

namespace ferry::builtin {
namespace {

constexpr float kHillHeight = 48;
constexpr float kGroundCap = 80;  // soft ceiling of the ground heightfield

// Turns an angle difference into [0, 2 pi).
float wrapAngle(float a) {
  float turns = a / (2 * kPi);
  return (turns - std::floor(turns)) * 2 * kPi;
}

}  // namespace

IslandShape::IslandShape(uint32_t seed) : seed_(seed) {
  coastTable_.resize(kCoastSamples + 1);
  for (int i = 0; i <= kCoastSamples; ++i) {
    float theta = -kPi + 2 * kPi * float(i % kCoastSamples) / float(kCoastSamples);
    float n = fbm(1.5f * std::cos(theta) + 10, 1.5f * std::sin(theta) + 10, seed + 11, 4);
    coastTable_[i] = kCoastRadius * (1 + kCoastVariation * std::clamp(n, -1.0f, 1.0f));
  }
  // isMountainA, the high volcano to the north-west, and isMountainB, a lower
  // one to the north-east; their skirts meet in a saddle.
  peaks[0] = {{-0.15f * kCoastRadius, -0.42f * kCoastRadius},
              0.6f * kCoastRadius,
              kPeakHeight,
              -25,
              seed + 41};
  peaks[1] = {
      {0.36f * kCoastRadius, -0.3f * kCoastRadius}, 0.4f * kCoastRadius, 190, -25, seed + 47};
  // isLavaRocks: three cliffs on the west, north-east and east shores.
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
  heroSpot = polar(1.5f, 0.8f);
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

float IslandShape::coast(float theta) const {
  float x = wrapAngle(theta + kPi) / (2 * kPi) * float(kCoastSamples);
  int i = std::clamp(int(x), 0, kCoastSamples - 1);
  return lerpf(coastTable_[i], coastTable_[i + 1], x - float(i));
}

Vec2f IslandShape::polar(float theta, float rho) const {
  float r = coast(theta) * rho;
  return {r * std::cos(theta), r * std::sin(theta)};
}

IslandShape::Where IslandShape::where(float x, float z) const {
  float theta = std::atan2(z, x);
  return {theta, std::sqrt(x * x + z * z) / coast(theta)};
}

float IslandShape::coastProfile(float rho) {
  float shelf = 2.6f * (1 - smoothstep(0.84f, 1.02f, rho));
  float dip = -0.8f * smoothstep(0.96f, 1.06f, rho);
  float drop = kSeabed * smoothstep(1.0f, 1.4f, rho);
  return shelf + dip + drop;
}

float IslandShape::ground(float x, float z) const {
  return groundAt(x, z, where(x, z).rho);
}

float IslandShape::groundAt(float x, float z, float r) const {
  float inland = smoothstep(0.93f, 0.2f, r);
  float hills =
      kHillHeight * std::pow(inland, 1.4f) * (0.55f + 0.45f * fbm(x / 170, z / 170, seed_ + 21, 5));
  float detail = 2.0f * fbm(x / 30, z / 30, seed_ + 31, 3) * smoothstep(0.95f, 0.75f, r);
  float h = coastProfile(r) + hills + detail;
  // The floor stays just above the seabed plane, which it would otherwise
  // touch and flicker with.
  return h > 0 ? kGroundCap * std::tanh(h / kGroundCap) : std::max(h, kSeabed + 0.5f);
}

float IslandShape::peakAt(int k, float x, float z, float u) const {
  const Peak& p = peaks[size_t(k)];
  u = std::clamp(u, 0.0f, 1.0f);
  // Ridges radiate from the summit: noise around the axis, bending slowly
  // with the distance from it.
  float angle = std::atan2(z - p.centre.y, x - p.centre.x);
  float n = fbm(4 * std::cos(angle) + 1.5f * u, 4 * std::sin(angle) + 1.5f * u, p.seed, 4);
  float ridge = std::clamp(1 - std::abs(n), 0.0f, 1.0f);
  ridge *= ridge;
  float gullies = 3.0f * fbm(x / 15, z / 15, p.seed + 2, 3) * 4 * u * (1 - u);
  // Profile and multiplier are at most 1 and exactly 1 at the axis, and the
  // gullies vanish there: the apex is the top.
  return p.base + (p.height - p.base) * std::pow(1 - u, 1.6f) * (1 - 0.6f * u * (1 - ridge)) +
         gullies;
}

float IslandShape::peak(int k, float x, float z) const {
  const Peak& p = peaks[size_t(k)];
  float dx = x - p.centre.x, dz = z - p.centre.y;
  float u = std::sqrt(dx * dx + dz * dz) / p.radius;
  return u < 1 ? peakAt(k, x, z, u) : kNoHeight;
}

// A smooth sand layer just above the shelf; it dives under the ground at
// its inner edge and ends, and under the sea at its outer edge.
float IslandShape::beachAt(float theta, float rho) {
  float edge = smoothstep(kBeachTheta0, kBeachTheta0 + 0.15f, theta) *
               smoothstep(kBeachTheta1, kBeachTheta1 - 0.15f, theta) *
               smoothstep(kBeachRho0, kBeachRho0 + 0.04f, rho);
  return coastProfile(rho) + 0.3f - 3.0f * (1 - edge);
}

float IslandShape::beachIn(Where w) {
  if (w.theta < kBeachTheta0 || w.theta > kBeachTheta1) return kNoHeight;
  if (w.rho < kBeachRho0 || w.rho > kBeachRho1) return kNoHeight;
  return beachAt(w.theta, w.rho);
}

float IslandShape::surface(float x, float z, Where w) const {
  float peaksTop = std::max(peak(0, x, z), peak(1, x, z));
  return std::max(groundAt(x, z, w.rho), std::max(peaksTop, beachIn(w)));
}

float IslandShape::surface(float x, float z) const {
  return surface(x, z, where(x, z));
}

bool IslandShape::inCliff(Vec2f p, float margin) const {
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

bool IslandShape::excluded(Vec2f p, bool groundCover) const {
  if (inCliff(p, 4)) return true;
  for (const Spot& s : spots) {
    if (groundCover && !s.groundCoverToo) continue;
    float dx = p.x - s.at.x, dz = p.y - s.at.y;
    if (dx * dx + dz * dz < s.radius * s.radius) return true;
  }
  return false;
}

bool IslandShape::inRegion(const Region& r, Vec2f p, Where w) const {
  if (r.kind == Region::Kind::OnPeak) {
    const Peak& k = peaks[size_t(r.peak)];
    float dx = p.x - k.centre.x, dz = p.y - k.centre.y;
    float u = std::sqrt(dx * dx + dz * dz) / k.radius;
    return u >= r.rho0 && u <= r.rho1;
  }
  if (r.kind == Region::Kind::NearCliffs) return inCliff(p, 40);
  if (w.rho < r.rho0 || w.rho > r.rho1) return false;
  return wrapAngle(w.theta - r.theta0) <= r.theta1 - r.theta0;
}

Ground regionGround(const Shape& shape, const Region& region) {
  Ground g;
  g.sample = [shape, region](HashRng& rng) {
    float theta = rng.uniform(region.theta0, region.theta1);
    float rho =
        std::sqrt(lerpf(region.rho0 * region.rho0, region.rho1 * region.rho1, rng.uniform()));
    if (region.kind == Region::Kind::Band) return shape->polar(theta, rho);
    if (region.kind == Region::Kind::NearCliffs) {
      const auto& cliffs = shape->cliffs;
      const Cliff& c =
          cliffs[std::min(cliffs.size() - 1, size_t(rng.uniform() * float(cliffs.size())))];
      return c.centre + rng.inDisc() * (c.rock.radii.x * (1 + c.rock.roughness) + 40);
    }
    const Peak& k = shape->peaks[size_t(region.peak)];
    return k.centre + Vec2f{std::cos(theta), std::sin(theta)} * (rho * k.radius);
  };
  g.accept = [shape, region](Vec2f p, float& y) {
    IslandShape::Where w = shape->where(p.x, p.y);
    if (!shape->inRegion(region, p, w) || shape->excluded(p, region.groundCover)) return false;
    y = shape->surface(p.x, p.y, w);
    return y >= region.yMin && y <= region.yMax;
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
  float n = fbm(x / 9, z / 9, seed + 51, 3);
  float coarse = fbm(x / 60, z / 60, seed + 53, 2);
  if (y < 0) return lerp(wetSand, deep, smoothstep(0.0f, 25.0f, -y)) * (0.9f + 0.1f * n);
  Vec3f green = lerp(grass, forestFloor, std::clamp(0.5f + 0.8f * coarse, 0.0f, 1.0f));
  Vec3f c = lerp(green, moss, smoothstep(80.0f, 150.0f, y));
  c = lerp(c, rock, smoothstep(150.0f, 200.0f, y + 20 * n));
  float sandiness = smoothstep(0.8f, 0.87f, w.rho + 0.03f * n) * (1 - smoothstep(2.5f, 4.5f, y));
  c = lerp(c, lerp(sand, wetSand, smoothstep(0.6f, 0.1f, y)), sandiness);
  return c * (0.85f + 0.15f * n);
}

}  // namespace ferry::builtin
