#include "builtin/plants.h"

#include <cmath>

#include <fmt/format.h>

#include "builtin/noise.h"
#include "core/error.h"

namespace ferry::builtin {

MeshCounts designCounts(const PlantDesign& design) {
  MeshCounts c;
  for (const PlantPart& p : design) c += p.counts;
  return c;
}

namespace {

constexpr float kGoldenAngle = 2.39996323f;

float radians(float degrees) {
  return degrees * kPi / 180.0f;
}

// Rotates `v` about the unit `axis` (Rodrigues).
Vec3f rotateAbout(Vec3f v, Vec3f axis, float angle) {
  float c = std::cos(angle), s = std::sin(angle);
  return v * c + cross(axis, v) * s + axis * (dot(axis, v) * (1 - c));
}

// ---------------------------------------------------------------- trees

struct Branch {
  std::vector<Vec3f> points;
  std::vector<float> radii;
  float length = 0;
};

// Point and radius at fraction t along a branch.
void sampleBranch(const Branch& b, float t, Vec3f& point, float& radius, Vec3f& tangent) {
  float x = std::clamp(t, 0.0f, 1.0f) * float(b.points.size() - 1);
  size_t i = std::min(size_t(x), b.points.size() - 2);
  float f = x - float(i);
  point = lerp(b.points[i], b.points[i + 1], f);
  radius = b.radii[i] + (b.radii[i + 1] - b.radii[i]) * f;
  Vec3f d = b.points[i + 1] - b.points[i];
  float len = length(d);
  tangent = len > 0 ? d / len : Vec3f(0, 1, 0);
}

Branch growBranch(Vec3f start, Vec3f dir, float length, float radius, const BranchLevel& level,
                  HashRng& rng) {
  Branch b;
  b.length = length;
  const int rings = level.rings;
  const float step = length / float(rings - 1);
  Vec3f wiggleAxis = perpendicular(dir);
  Vec3f p = start;
  for (int i = 0; i < rings; ++i) {
    float t = float(i) / float(rings - 1);
    b.points.push_back(p);
    b.radii.push_back(radius * (1 - (1 - level.taper) * t));
    // Bend towards (or away from) the sky, with a little wander.
    dir = normalize(dir + Vec3f(0, level.gravity * 2.0f / float(rings), 0) +
                    rotateAbout(wiggleAxis, dir, rng.uniform(0, 2 * kPi)) * 0.08f);
    p = p + dir * step;
  }
  return b;
}

// The whole skeleton; levels[k] holds the branches of level k (0: trunk).
std::vector<std::vector<Branch>> growTree(const TreeParams& p, uint32_t seed) {
  HashRng rng(seed, 0x7ee);
  std::vector<std::vector<Branch>> levels(1);
  {
    Branch trunk;
    trunk.length = p.trunkLength;
    float leanAzimuth = rng.uniform(0, 2 * kPi);
    Vec3f leanDir{std::cos(leanAzimuth), 0, std::sin(leanAzimuth)};
    float phase = rng.uniform(0, 10);
    for (int i = 0; i < p.trunkRings; ++i) {
      float t = float(i) / float(p.trunkRings - 1);
      Vec3f wander{gradientNoise(t * 2.5f, phase, seed), 0,
                   gradientNoise(phase, t * 2.5f, seed + 1)};
      Vec3f offset = (leanDir * (t * t) * p.trunkLean + wander * (0.04f * t)) * p.trunkLength;
      trunk.points.push_back(Vec3f(0, -0.1f * p.trunkRadius + t * p.trunkLength, 0) + offset);
      float flare = 1 + p.trunkFlare * std::pow(1 - t, 6.0f);
      trunk.radii.push_back(p.trunkRadius * (1 - (1 - p.trunkTaper) * t) * flare);
    }
    levels[0].push_back(std::move(trunk));
  }
  for (const BranchLevel& level : p.levels) {
    std::vector<Branch> next;
    for (const Branch& parent : levels.back()) {
      float azimuth0 = rng.uniform(0, 2 * kPi);
      for (int k = 0; k < level.children; ++k) {
        float t = level.startFraction + (1 - level.startFraction) *
                                            (float(k) + 0.5f + rng.uniform(-0.3f, 0.3f)) /
                                            float(level.children);
        t = std::clamp(t, level.startFraction, 0.97f);
        Vec3f at, tangent;
        float parentRadius;
        sampleBranch(parent, t, at, parentRadius, tangent);
        Vec3f side1 = perpendicular(tangent), side2 = cross(tangent, side1);
        float azimuth = azimuth0 + kGoldenAngle * float(k) + rng.uniform(-0.3f, 0.3f);
        Vec3f out = side1 * std::cos(azimuth) + side2 * std::sin(azimuth);
        float spread = radians(level.spreadDegrees) * rng.uniform(0.8f, 1.2f);
        Vec3f dir = normalize(tangent * std::cos(spread) + out * std::sin(spread));
        float len =
            parent.length * level.lengthRatio * (1 - p.coneFactor * t) * rng.uniform(0.8f, 1.15f);
        len = std::max(len, 0.05f * parent.length);
        next.push_back(growBranch(at, dir, len, parentRadius * level.radiusRatio, level, rng));
      }
    }
    levels.push_back(std::move(next));
  }
  return levels;
}

uint64_t branchCount(const TreeParams& p, size_t level) {
  uint64_t n = 1;
  for (size_t k = 0; k < level; ++k) n *= uint64_t(p.levels[k].children);
  return n;
}

void addBranchTube(MeshBuilder& b, const Branch& branch, int sides) {
  float r = std::max(branch.radii.front(), 0.01f);
  addTube(b, branch.points, branch.radii, sides, 1.0f / (2 * kPi * r) * 0.5f);
}

// The wood of one level (0: the trunk and the aerial roots), or of all with kAllLevels.
constexpr int kAllLevels = -1;

MeshCounts woodLevelCounts(const TreeParams& p, int level) {
  if (level == 0)
    return tubeCounts(p.trunkRings, p.trunkSides) +
           tubeCounts(p.rootRings, p.rootSides) * uint64_t(p.aerialRoots);
  const BranchLevel& l = p.levels[size_t(level - 1)];
  return tubeCounts(l.rings, l.sides) * branchCount(p, size_t(level));
}

// Leaves of the tip branches [tipBegin, tipEnd).
MeshCounts leafRunCounts(const TreeParams& p, uint64_t tipBegin, uint64_t tipEnd) {
  return ribbonCounts(p.leafSegments) * ((tipEnd - tipBegin) * uint64_t(p.leavesPerTip));
}

Mesh buildTreeWood(const TreeParams& p, uint32_t seed, int only) {
  auto levels = growTree(p, seed);
  MeshCounts counts = only == kAllLevels ? treeWoodCounts(p) : woodLevelCounts(p, only);
  MeshBuilder b(true, true, counts);
  auto wanted = [only](size_t level) { return only == kAllLevels || size_t(only) == level; };
  if (wanted(0)) addBranchTube(b, levels[0][0], p.trunkSides);
  for (size_t k = 0; k < p.levels.size(); ++k)
    if (wanted(k + 1))
      for (const Branch& br : levels[k + 1]) addBranchTube(b, br, p.levels[k].sides);
  if (p.aerialRoots > 0 && wanted(0)) {
    // Roots hang from the first branch level (or the trunk) down into the ground.
    const std::vector<Branch>& hosts = levels.size() > 1 ? levels[1] : levels[0];
    HashRng rng(seed, 0x2007);
    for (int r = 0; r < p.aerialRoots; ++r) {
      const Branch& host = hosts[size_t(r) % hosts.size()];
      Vec3f top, tangent;
      float hostRadius;
      sampleBranch(host, rng.uniform(0.2f, 0.95f), top, hostRadius, tangent);
      float bottom = std::min(top.y - 0.5f, -0.2f);
      Vec2f drift = rng.inDisc() * 0.4f;
      float radius = p.rootRadius * rng.uniform(0.6f, 1.5f);
      std::vector<Vec3f> pts(p.rootRings);
      std::vector<float> radii(p.rootRings);
      for (int i = 0; i < p.rootRings; ++i) {
        float t = float(i) / float(p.rootRings - 1);
        float sway = std::sin(t * kPi);
        pts[i] = {top.x + drift.x * sway, top.y + (bottom - top.y) * t, top.z + drift.y * sway};
        radii[i] = radius * (0.5f + 0.7f * t * t);  // thickening where it roots
      }
      addTube(b, pts, radii, p.rootSides, 1.0f);
    }
  }
  return b.finish();
}

// Draws every leaf's random numbers in the same order whatever the run, so a
// tree cut into leaf meshes has the same leaves as one in one mesh.
Mesh buildTreeLeaves(const TreeParams& p, uint32_t seed, uint64_t tipBegin, uint64_t tipEnd) {
  auto levels = growTree(p, seed);
  MeshBuilder b(true, true, leafRunCounts(p, tipBegin, tipEnd));
  HashRng rng(seed, 0x1eaf);
  const int segs = p.leafSegments;
  std::vector<Vec3f> centres(segs + 1), sides(segs + 1);
  std::vector<float> widths(segs + 1);
  for (uint64_t t = 0; t < levels.back().size(); ++t) {
    const Branch& tip = levels.back()[t];
    const bool emit = t >= tipBegin && t < tipEnd;
    for (int k = 0; k < p.leavesPerTip; ++k) {
      Vec3f at, tangent;
      float radius;
      sampleBranch(tip, 1 - p.leafSpread * rng.uniform(), at, radius, tangent);
      Vec3f dir = normalize(tangent * 0.6f + rng.onSphere() + Vec3f(0, 0.3f, 0));
      Vec3f side = cross(dir, rng.onSphere());
      side = length(side) > 1e-4f ? normalize(side) : perpendicular(dir);
      float size = p.leafSize * rng.uniform(0.8f, 1.2f);
      for (int i = 0; i <= segs; ++i) {
        float s = float(i) / float(segs);
        centres[i] = at + dir * (size * s) - Vec3f(0, p.leafDroop * size * s * s, 0);
        sides[i] = side;
        widths[i] = size;
      }
      if (emit) addRibbon(b, centres, sides, widths);
    }
  }
  return b.finish();
}

// ---------------------------------------------------------------- fronds

// A frond (palm or fern): a spine arching out from `base` and drooping, with
// two half-ribbons in a shallow V; u = 0.5 is the rachis in the texture.
void addFrond(MeshBuilder& b, Vec3f base, float azimuth, float elevation, float droop, float length,
              float width, int segments, float vAngle) {
  Vec3f horizontal{std::cos(azimuth), 0, std::sin(azimuth)};
  Vec3f side{-std::sin(azimuth), 0, std::cos(azimuth)};
  std::vector<Vec3f> spine(segments + 1);
  Vec3f p = base;
  const float step = length / float(segments);
  for (int i = 0; i <= segments; ++i) {
    spine[i] = p;
    float e = elevation - droop * float(i) / float(segments);
    p = p + (horizontal * std::cos(e) + Vec3f(0, std::sin(e), 0)) * step;
  }
  for (int half = 0; half < 2; ++half) {
    float sign = half == 0 ? -1.0f : 1.0f;
    Vec3f outward = normalize(side * (sign * std::cos(vAngle)) + Vec3f(0, std::sin(vAngle), 0));
    std::vector<Vec3f> centres(segments + 1), sides(segments + 1, outward);
    std::vector<float> widths(segments + 1);
    for (int i = 0; i <= segments; ++i) {
      float s = float(i) / float(segments);
      float w = 0.5f * width * std::pow(std::sin(kPi * (0.06f + 0.9f * s)), 0.7f);
      widths[i] = w;
      centres[i] = spine[i] + outward * (0.5f * w);
    }
    // The strip runs from the rachis (u = 0.5) to the edge (u = 0 or 1).
    addRibbon(b, centres, sides, widths, 0.5f, half == 0 ? 0.0f : 1.0f);
  }
}

MeshCounts frondCounts(int segments) {
  return ribbonCounts(segments) * 2;
}

}  // namespace

// ------------------------------------------------------------------ trees

MeshCounts treeWoodCounts(const TreeParams& p) {
  MeshCounts c;
  for (size_t level = 0; level <= p.levels.size(); ++level) c += woodLevelCounts(p, int(level));
  return c;
}

PlantDesign designTree(const TreeParams& p, uint32_t seed) {
  FERRY_CHECK_GE(p.trunkRings, 2);
  FERRY_CHECK_GE(p.trunkSides, 3);
  FERRY_CHECK_GE(p.leafSegments, 1);
  for (const BranchLevel& l : p.levels) {
    FERRY_CHECK_GE(l.children, 1);
    FERRY_CHECK_GE(l.rings, 2);
    FERRY_CHECK_GE(l.sides, 3);
  }
  FERRY_CHECK_GE(p.leafMeshes, 1);
  PlantDesign d;
  if (p.woodByLevel) {
    for (int level = 0; level <= int(p.levels.size()); ++level)
      d.push_back({level == 0 ? std::string("trunk") : fmt::format("branches-{}", level),
                   PartRole::Wood, woodLevelCounts(p, level), true, true,
                   [p, seed, level] { return buildTreeWood(p, seed, level); }, level});
  } else {
    d.push_back({"wood", PartRole::Wood, treeWoodCounts(p), true, true,
                 [p, seed] { return buildTreeWood(p, seed, kAllLevels); }});
  }
  if (p.leavesPerTip > 0) {
    const uint64_t tips = branchCount(p, p.levels.size());
    const uint64_t runs = std::min<uint64_t>(uint64_t(p.leafMeshes), tips);
    for (uint64_t r = 0; r < runs; ++r) {
      uint64_t begin = tips * r / runs, end = tips * (r + 1) / runs;
      d.push_back({runs == 1 ? std::string("leaves") : fmt::format("leaves-{}", r),
                   PartRole::Leaves, leafRunCounts(p, begin, end), true, true,
                   [p, seed, begin, end] { return buildTreeLeaves(p, seed, begin, end); }, int(r)});
    }
  }
  return d;
}

// ------------------------------------------------------------------ palms

PlantDesign designPalm(const PalmParams& p, uint32_t seed) {
  FERRY_CHECK_GE(p.trunkRings, 2);
  FERRY_CHECK_GE(p.fronds, 1);
  FERRY_CHECK_GE(p.frondSegments, 1);
  // The trunk and crown share one curve; all parts recompute it from the seed.
  auto trunkCurve = [p, seed](std::vector<Vec3f>& pts, std::vector<float>& radii) {
    HashRng rng(seed, 0xba1);
    float azimuth = rng.uniform(0, 2 * kPi);
    Vec3f leanDir{std::cos(azimuth), 0, std::sin(azimuth)};
    float lean = p.lean * rng.uniform(0.5f, 1.2f);
    pts.resize(p.trunkRings);
    radii.resize(p.trunkRings);
    for (int i = 0; i < p.trunkRings; ++i) {
      float t = float(i) / float(p.trunkRings - 1);
      pts[i] = Vec3f(0, -0.15f + t * p.height, 0) + leanDir * (lean * p.height * t * t);
      radii[i] = p.trunkRadius * (1.3f - 0.4f * t) * (1 + 0.5f * std::pow(1 - t, 8.0f));
    }
  };
  PlantDesign d;
  d.push_back({"trunk", PartRole::Wood, tubeCounts(p.trunkRings, p.trunkSides), true, true,
               [p, trunkCurve] {
                 std::vector<Vec3f> pts;
                 std::vector<float> radii;
                 trunkCurve(pts, radii);
                 MeshBuilder b(true, true, tubeCounts(p.trunkRings, p.trunkSides));
                 addTube(b, pts, radii, p.trunkSides, 0.25f);
                 return b.finish();
               }});
  d.push_back({"fronds", PartRole::Fronds, frondCounts(p.frondSegments) * uint64_t(p.fronds), true,
               true, [p, seed, trunkCurve] {
                 std::vector<Vec3f> pts;
                 std::vector<float> radii;
                 trunkCurve(pts, radii);
                 HashRng rng(seed, 0xf20);
                 MeshBuilder b(true, true, frondCounts(p.frondSegments) * uint64_t(p.fronds));
                 for (int f = 0; f < p.fronds; ++f) {
                   float azimuth = kGoldenAngle * float(f) + rng.uniform(-0.2f, 0.2f);
                   // Young fronds stand up, old ones hang.
                   float age = float(f) / float(p.fronds);
                   float elevation = lerpf(1.1f, -0.1f, age) + rng.uniform(-0.15f, 0.15f);
                   float droop = lerpf(0.9f, 1.6f, age);
                   addFrond(b, pts.back(), azimuth, elevation, droop,
                            p.frondLength * rng.uniform(0.85f, 1.1f), p.frondWidth, p.frondSegments,
                            0.35f);
                 }
                 return b.finish();
               }});
  if (p.coconuts > 0) {
    MeshCounts nuts = cubeSphereCounts(p.coconutDetail) * uint64_t(p.coconuts);
    d.push_back({"coconuts", PartRole::Fruit, nuts, true, true, [p, seed, trunkCurve, nuts] {
                   std::vector<Vec3f> pts;
                   std::vector<float> radii;
                   trunkCurve(pts, radii);
                   HashRng rng(seed, 0xc0c0);
                   MeshBuilder b(true, true, nuts);
                   for (int k = 0; k < p.coconuts; ++k) {
                     float a = 2 * kPi * float(k) / float(p.coconuts) + rng.uniform(-0.3f, 0.3f);
                     float r = 0.12f * rng.uniform(0.85f, 1.1f);
                     Vec3f c =
                         pts.back() + Vec3f(std::cos(a) * 0.2f, -0.25f - rng.uniform(0, 0.15f),
                                            std::sin(a) * 0.2f);
                     addCubeSphere(b, p.coconutDetail, [c, r](Vec3f dir) {
                       return c + Vec3f(dir.x, dir.y * 1.15f, dir.z) * r;
                     });
                   }
                   return b.finish();
                 }});
  }
  return d;
}

// ------------------------------------------------------------------ ferns

PlantDesign designFern(const FernParams& p, uint32_t seed) {
  FERRY_CHECK_GE(p.fronds, 1);
  FERRY_CHECK_GE(p.segments, 1);
  MeshCounts counts = frondCounts(p.segments) * uint64_t(p.fronds);
  PlantDesign d;
  d.push_back({"fronds", PartRole::Fronds, counts, true, true, [p, seed, counts] {
                 HashRng rng(seed, 0xfe2);
                 MeshBuilder b(true, true, counts);
                 for (int f = 0; f < p.fronds; ++f) {
                   float azimuth = kGoldenAngle * float(f) + rng.uniform(-0.3f, 0.3f);
                   float elevation = rng.uniform(0.5f, 1.25f);
                   addFrond(b, Vec3f(0, 0.02f, 0), azimuth, elevation, rng.uniform(0.9f, 1.5f),
                            p.length * rng.uniform(0.7f, 1.1f), p.width, p.segments, 0.25f);
                 }
                 return b.finish();
               }});
  return d;
}

// ------------------------------------------------------------------ grass

PlantDesign designGrass(const GrassParams& p, uint32_t seed) {
  FERRY_CHECK_GE(p.blades, 1);
  FERRY_CHECK_GE(p.segments, 1);
  MeshCounts counts = ribbonCounts(p.segments) * uint64_t(p.blades);
  PlantDesign d;
  d.push_back({"blades", PartRole::Blades, counts, true, true, [p, seed, counts] {
                 HashRng rng(seed, 0x9a55);
                 MeshBuilder b(true, true, counts);
                 const int n = p.segments;
                 std::vector<Vec3f> centres(n + 1), sides(n + 1);
                 std::vector<float> widths(n + 1);
                 for (int k = 0; k < p.blades; ++k) {
                   Vec2f base = rng.inDisc() * p.radius;
                   float azimuth = std::atan2(base.y, base.x) + rng.uniform(-0.6f, 0.6f);
                   Vec3f out{std::cos(azimuth), 0, std::sin(azimuth)};
                   float lean = rng.uniform(0.05f, 0.5f), bend = rng.uniform(0.3f, 1.2f);
                   float h = p.height * rng.uniform(0.55f, 1.15f);
                   Vec3f side = normalize(Vec3f(-out.z, 0, out.x) + out * rng.uniform(-0.5f, 0.5f));
                   Vec3f pos{base.x, -0.03f, base.y};
                   for (int i = 0; i <= n; ++i) {
                     float s = float(i) / float(n);
                     centres[i] = pos;
                     sides[i] = side;
                     widths[i] = p.width * (1 - 0.85f * s);
                     float e = lean + bend * s;  // angle from vertical grows towards the tip
                     pos = pos + (Vec3f(0, std::cos(e), 0) + out * std::sin(e)) * (h / float(n));
                   }
                   addRibbon(b, centres, sides, widths);
                 }
                 return b.finish();
               }});
  return d;
}

// ---------------------------------------------------------------- flowers

PlantDesign designFlowers(const FlowerParams& p, uint32_t seed) {
  FERRY_CHECK_GE(p.stems, 1);
  FERRY_CHECK_GE(p.stemRings, 2);
  FERRY_CHECK_GE(p.stemSides, 3);
  FERRY_CHECK_GE(p.petals, 1);
  // Stem curves are shared by all parts, recomputed from the seed.
  auto stemCurve = [p, seed](int k, std::vector<Vec3f>& pts, std::vector<float>& radii) {
    HashRng rng(seed, 0x57e, uint32_t(k));
    Vec2f base = rng.inDisc() * p.spread;
    Vec2f tilt = rng.inDisc() * 0.35f;
    float h = p.height * rng.uniform(0.7f, 1.15f);
    pts.resize(p.stemRings);
    radii.resize(p.stemRings);
    for (int i = 0; i < p.stemRings; ++i) {
      float t = float(i) / float(p.stemRings - 1);
      pts[i] = {base.x + tilt.x * h * t * t, -0.02f + h * t, base.y + tilt.y * h * t * t};
      radii[i] = 0.004f * (1.2f - 0.4f * t);
    }
  };
  MeshCounts stems = tubeCounts(p.stemRings, p.stemSides) * uint64_t(p.stems);
  MeshCounts leaves = ribbonCounts(1) * uint64_t(p.stems) * uint64_t(p.leavesPerStem);
  MeshCounts petals = ribbonCounts(1) * uint64_t(p.stems) * uint64_t(p.petals);
  MeshCounts centres = cubeSphereCounts(p.centreDetail) * uint64_t(p.stems);
  PlantDesign d;
  d.push_back({"stems", PartRole::Stems, stems, true, true, [p, stemCurve, stems] {
                 MeshBuilder b(true, true, stems);
                 std::vector<Vec3f> pts;
                 std::vector<float> radii;
                 for (int k = 0; k < p.stems; ++k) {
                   stemCurve(k, pts, radii);
                   addTube(b, pts, radii, p.stemSides, 4.0f);
                 }
                 return b.finish();
               }});
  if (p.leavesPerStem > 0)
    d.push_back({"leaves", PartRole::Leaves, leaves, true, true, [p, seed, stemCurve, leaves] {
                   MeshBuilder b(true, true, leaves);
                   std::vector<Vec3f> pts;
                   std::vector<float> radii;
                   for (int k = 0; k < p.stems; ++k) {
                     stemCurve(k, pts, radii);
                     HashRng rng(seed, 0x1ea, uint32_t(k));
                     for (int l = 0; l < p.leavesPerStem; ++l) {
                       Vec3f at = lerp(pts.front(), pts.back(), rng.uniform(0.05f, 0.5f));
                       float a = rng.uniform(0, 2 * kPi);
                       Vec3f out{std::cos(a), 0.6f, std::sin(a)};
                       float size = p.height * 0.3f;
                       Vec3f centres[2] = {at, at + normalize(out) * size};
                       Vec3f side = normalize(Vec3f(-std::sin(a), 0, std::cos(a)));
                       Vec3f sides[2] = {side, side};
                       float widths[2] = {size, size};
                       addRibbon(b, centres, sides, widths);
                     }
                   }
                   return b.finish();
                 }});
  d.push_back({"petals", PartRole::Petals, petals, true, true, [p, seed, stemCurve, petals] {
                 MeshBuilder b(true, true, petals);
                 std::vector<Vec3f> pts;
                 std::vector<float> radii;
                 for (int k = 0; k < p.stems; ++k) {
                   stemCurve(k, pts, radii);
                   HashRng rng(seed, 0x9e7, uint32_t(k));
                   float a0 = rng.uniform(0, 2 * kPi);
                   for (int q = 0; q < p.petals; ++q) {
                     float a = a0 + 2 * kPi * float(q) / float(p.petals);
                     Vec3f out =
                         normalize(Vec3f(std::cos(a), rng.uniform(0.1f, 0.45f), std::sin(a)));
                     Vec3f side{-std::sin(a), 0, std::cos(a)};
                     float len = p.petalLength * rng.uniform(0.85f, 1.1f);
                     Vec3f centres[2] = {pts.back(), pts.back() + out * len};
                     Vec3f sides[2] = {side, side};
                     float widths[2] = {0.7f * len, 0.7f * len};
                     addRibbon(b, centres, sides, widths);
                   }
                 }
                 return b.finish();
               }});
  d.push_back({"centres", PartRole::FlowerCentre, centres, true, true, [p, stemCurve, centres] {
                 MeshBuilder b(true, true, centres);
                 std::vector<Vec3f> pts;
                 std::vector<float> radii;
                 for (int k = 0; k < p.stems; ++k) {
                   stemCurve(k, pts, radii);
                   Vec3f c = pts.back();
                   float r = p.centreRadius;
                   addCubeSphere(b, p.centreDetail, [c, r](Vec3f dir) {
                     return c + Vec3f(dir.x, dir.y * 0.6f, dir.z) * r;
                   });
                 }
                 return b.finish();
               }});
  return d;
}

// ---------------------------------------------------------------- patches

namespace {

// Where clump k of a patch stands, and how it is turned and scaled.
Affine3f clumpPlacement(const PatchParams& p, uint32_t seed, int k) {
  HashRng rng(seed, 0x9a7c, uint32_t(k));
  Vec2f at = rng.inDisc() * p.radius;
  float yaw = rng.uniform(0, 2 * kPi);
  float scale = rng.uniform(p.scaleMin, p.scaleMax);
  return Affine3f::translate({at.x, 0, at.y}) * Affine3f::rotate({0, 1, 0}, yaw) *
         Affine3f::scale(Vec3f(scale));
}

void appendTransformed(MeshBuilder& b, const Mesh& m, const Affine3f& to) {
  const int32_t first = b.vertexCount();
  for (size_t v = 0; v < m.positions.size(); ++v)
    b.vertex(to.transformPoint(m.positions[v]),
             m.normals.empty() ? Vec3f(0, 1, 0) : normalize(to.transformNormal(m.normals[v])),
             m.uvs.empty() ? Vec2f(0, 0) : m.uvs[v]);
  for (const Vec3i& t : m.indices) b.triangle(first + t.x, first + t.y, first + t.z);
}

}  // namespace

PlantDesign designPatch(const PatchParams& p, const std::function<PlantDesign(int)>& clump,
                        uint32_t seed) {
  FERRY_CHECK_GE(p.clumps, 1);
  FERRY_CHECK_GE(p.groups, 1);
  FERRY_CHECK_LE(p.groups, p.clumps);
  std::vector<PlantDesign> clumps(size_t(p.clumps));
  for (int k = 0; k < p.clumps; ++k) {
    clumps[size_t(k)] = clump(k);
    FERRY_CHECK_EQ(clumps[size_t(k)].size(), clumps[0].size());
    for (size_t j = 0; j < clumps[0].size(); ++j)
      FERRY_CHECK(clumps[size_t(k)][j].role == clumps[0][j].role);
  }
  PlantDesign d;
  for (int g = 0; g < p.groups; ++g) {
    const int begin = p.clumps * g / p.groups, end = p.clumps * (g + 1) / p.groups;
    for (size_t j = 0; j < clumps[0].size(); ++j) {
      MeshCounts counts;
      for (int k = begin; k < end; ++k) counts += clumps[size_t(k)][j].counts;
      const PlantPart& part = clumps[0][j];
      d.push_back(
          {fmt::format("{}/{}", g, part.name), part.role, counts, part.hasNormals, part.hasUvs,
           [p, clump, seed, begin, end, j, counts, normals = part.hasNormals, uvs = part.hasUvs] {
             MeshBuilder b(normals, uvs, counts);
             for (int k = begin; k < end; ++k)
               appendTransformed(b, clump(k)[j].build(), clumpPlacement(p, seed, k));
             return b.finish();
           },
           g});
    }
  }
  return d;
}

// ------------------------------------------------------------------ rocks

Vec3f rockSurface(const RockParams& p, uint32_t seed, Vec3f dir) {
  float n =
      std::clamp(fbm(dir * p.frequency + Vec3f(float(seed % 97)), seed, p.octaves), -1.0f, 1.0f);
  Vec3f centre{0, p.radii.y * (1 - p.sink), 0};
  return centre + dir * p.radii * (1 + p.roughness * n);
}

PlantDesign designRock(const RockParams& p, uint32_t seed) {
  FERRY_CHECK_GE(p.detail, 1);
  PlantDesign d;
  d.push_back({"rock", PartRole::Rock, cubeSphereCounts(p.detail), true, true, [p, seed] {
                 MeshBuilder b(true, true, cubeSphereCounts(p.detail));
                 addCubeSphere(b, p.detail, [&](Vec3f dir) { return rockSurface(p, seed, dir); });
                 return b.finish();
               }});
  return d;
}

// ------------------------------------------------------------------- logs

PlantDesign designLog(const LogParams& p, uint32_t seed) {
  FERRY_CHECK_GE(p.rings, 2);
  FERRY_CHECK_GE(p.sides, 3);
  FERRY_CHECK_GE(p.stubRings, 2);
  FERRY_CHECK_GE(p.stubSides, 3);
  MeshCounts counts =
      tubeCounts(p.rings, p.sides) + tubeCounts(p.stubRings, p.stubSides) * uint64_t(p.stubs);
  PlantDesign d;
  d.push_back({"wood", PartRole::Wood, counts, true, true, [p, seed, counts] {
                 HashRng rng(seed, 0x109);
                 MeshBuilder b(true, true, counts);
                 std::vector<Vec3f> pts(p.rings);
                 std::vector<float> radii(p.rings);
                 float bend = rng.uniform(-0.15f, 0.15f) * p.length;
                 for (int i = 0; i < p.rings; ++i) {
                   float t = float(i) / float(p.rings - 1);
                   float s = std::sin(kPi * t);
                   pts[i] = {(t - 0.5f) * p.length, p.radius * 0.6f + 0.05f * p.length * s * 0.3f,
                             bend * s};
                   radii[i] = p.radius * (1.1f - 0.4f * t) * (1 + 0.08f * std::sin(17.0f * t));
                 }
                 addTube(b, pts, radii, p.sides, 0.5f);
                 for (int k = 0; k < p.stubs; ++k) {
                   float t = rng.uniform(0.15f, 0.85f);
                   int i = int(t * float(p.rings - 1));
                   float a = rng.uniform(0, 2 * kPi);
                   Vec3f dir = normalize(Vec3f(0.4f, std::cos(a), std::sin(a)));
                   float len = rng.uniform(0.2f, 0.6f) * p.length * 0.3f;
                   std::vector<Vec3f> sp(p.stubRings);
                   std::vector<float> sr(p.stubRings);
                   for (int j = 0; j < p.stubRings; ++j) {
                     float u = float(j) / float(p.stubRings - 1);
                     sp[j] = pts[i] + dir * (len * u);
                     sr[j] = radii[i] * 0.45f * (1 - 0.7f * u);
                   }
                   addTube(b, sp, sr, p.stubSides, 1.0f);
                 }
                 return b.finish();
               }});
  return d;
}

}  // namespace ferry::builtin
