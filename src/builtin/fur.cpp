#include "builtin/fur.h"

#include <cmath>

#include "builtin/noise.h"
#include "material/models/diffuse.h"
#include "material/models/hair.h"
#include "shapes/curves.h"

namespace ferry::builtin {
namespace {

constexpr float kStrandsPerCm2 = 300;
constexpr float kCapBelow = 0.4f;  // roots down to y = -0.4 R
constexpr float kRootWidth = 0.008f, kTipWidth = 0.002f;
constexpr float kMaxLength = 2;

// Strand i's 13 control points: a root spread evenly over the cap (a
// golden-angle spiral, jittered), rising along the normal and bending back
// and down.
std::array<Vec3f, 3 * kFurSegmentsPerStrand + 1> strand(uint64_t i, uint64_t n, float radius,
                                                        float length, uint32_t seed) {
  HashRng rng(seed, uint32_t(i), uint32_t(i >> 32));
  const float golden = 2.39996323f;
  const float y = 1 - (1 + kCapBelow) * (float(i) + rng.uniform()) / float(n);
  const float ring = std::sqrt(std::max(0.0f, 1 - y * y));
  const float phi = golden * float(i) + 0.3f * rng.uniform();
  const Vec3f normal{ring * std::cos(phi), y, ring * std::sin(phi)};
  Vec3f comb = Vec3f(0, -0.6f, -1) - normal * dot(Vec3f(0, -0.6f, -1), normal);
  comb = dot(comb, comb) > 1e-6f ? normalize(comb) : Frame(normal).s;
  const Vec3f side = cross(normal, comb);
  const float l = length * (0.8f + 0.4f * rng.uniform());
  const float lift = 0.45f + 0.3f * rng.uniform();
  const float sway = 0.4f * (rng.uniform() - 0.5f);
  std::array<Vec3f, 3 * kFurSegmentsPerStrand + 1> p;
  for (size_t k = 0; k < p.size(); ++k) {
    const float s = float(k) / float(p.size() - 1);
    p[k] = normal * radius + normal * (l * lift * s * (1 - 0.5f * s)) + comb * (l * 0.85f * s * s) +
           side * (l * sway * s * s);
  }
  return p;
}

}  // namespace

ScenePlan planFur(uint64_t strands, uint32_t seed) {
  ScenePlan plan;
  plan.name = "fur";
  const uint64_t n = std::max<uint64_t>(strands, 1);
  const float capArea = 2 * kPi * (1 + kCapBelow);  // per unit radius squared
  const float radius = std::sqrt(float(n) / (kStrandsPerCm2 * capArea));
  const float length = std::min(kMaxLength, 0.5f * radius);

  Material hair;
  hair.name = "hair";
  hair.baseColor = Vec3f(0.5f);
  auto model = std::make_shared<HairModel>();
  model->eumelanin = 0.8f;
  model->pheomelanin = 0.4f;
  hair.model = model;
  const int32_t hairMaterial = plan.addMaterial(hair);
  const int32_t skin = addDiffuseMaterial(plan, "skin", {0.35f, 0.22f, 0.15f});
  const int32_t grey = addDiffuseMaterial(plan, "studio", Vec3f(0.5f));

  const int latitudes = 48, longitudes = 96;
  MeshRecipe ball;
  ball.name = "ball";
  ball.material = skin;
  ball.counts = uvSphereCounts(latitudes, longitudes);
  ball.build = [=] {
    MeshBuilder b(true, true, uvSphereCounts(latitudes, longitudes));
    addUvSphere(b, latitudes, longitudes, {0, 0, 0}, radius);
    return b.finish();
  };
  plan.addSingleInstanceMesh(std::move(ball));
  // A floor under the ball and a backdrop behind it, 4 radii out: they span
  // the scene's bounds (the fur stays within 1.5 radii, above -0.9 radii).
  addStudio(plan, grey, 4 * radius, -radius, 3 * radius);

  ShapeRecipe fur;
  fur.name = "fur";
  fur.kind = "curves";
  fur.material = hairMaterial;
  fur.primitives = n * kFurSegmentsPerStrand;
  fur.piecesPerPrimitive = Curves::traversalPiecesFor(CurveType::Flat, fur.primitives);
  fur.bytes = fur.primitives * Curves::bytesPerSegment(CurveType::Flat);
  fur.accelBytesPerBox = MemoryModel::kAccelBytesPerFlatCurve;
  fur.build = [=] {
    std::vector<CurveSegment> segments(n * kFurSegmentsPerStrand);
    for (uint64_t i = 0; i < n; ++i) {
      const auto p = strand(i, n, radius, length, seed);
      for (int k = 0; k < kFurSegmentsPerStrand; ++k) {
        CurveSegment& s = segments[i * kFurSegmentsPerStrand + uint64_t(k)];
        s.points = {p[3 * k], p[3 * k + 1], p[3 * k + 2], p[3 * k + 3]};
        const float t0 = float(k) / kFurSegmentsPerStrand,
                    t1 = float(k + 1) / kFurSegmentsPerStrand;
        s.width0 = kRootWidth + (kTipWidth - kRootWidth) * t0;
        s.width1 = kRootWidth + (kTipWidth - kRootWidth) * t1;
        s.u0 = t0;
        s.u1 = t1;
      }
    }
    return std::make_shared<Curves>(CurveType::Flat, std::move(segments));
  };
  plan.shapes.push_back(std::move(fur));

  addDaylight(plan, {0.6f, 1, 0.8f}, {0.25f, 0.45f, 0.9f}, {0.8f, 0.85f, 0.95f}, {0.3f, 0.3f, 0.3f},
              0.3f);
  CameraView view;
  view.name = "default";
  view.from = {0, 0.6f * radius, 5.5f * radius};
  view.at = {0, 0.1f * radius, 0};
  view.fovY = 40;
  plan.views.push_back(view);
  return plan;
}

}  // namespace ferry::builtin
