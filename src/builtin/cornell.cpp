#include "builtin/cornell.h"

#include <array>
#include <cmath>
#include <vector>

namespace ferry::builtin {
namespace {

using Quad = std::array<Vec3f, 4>;

const Vec3f kBoxCentre{278, 274.4f, 279.6f};

// The published quads (corners in order around each quad).
const Quad kFloor = {{{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}}};
const Quad kCeiling = {
    {{556, 548.8f, 0}, {556, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}}};
const Quad kBackWall = {
    {{549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556, 548.8f, 559.2f}}};
const Quad kRightWall = {{{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}}};
const Quad kLeftWall = {
    {{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556, 548.8f, 559.2f}, {556, 548.8f, 0}}};
// The light is 0.5 below the ceiling rather than in its plane, so the two
// never compete for the same hit.
const Quad kLight = {
    {{343, 548.3f, 227}, {343, 548.3f, 332}, {213, 548.3f, 332}, {213, 548.3f, 227}}};
const std::array<Quad, 5> kShortBlock = {{
    {{{130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114}}},
    {{{290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272}}},
    {{{130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114}}},
    {{{82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65}}},
    {{{240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225}}},
}};
const std::array<Quad, 5> kTallBlock = {{
    {{{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}}},
    {{{423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406}}},
    {{{472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456}}},
    {{{314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296}}},
    {{{265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247}}},
}};

Vec3f quadCentre(const Quad& q) {
  return (q[0] + q[1] + q[2] + q[3]) * 0.25f;
}

// An n x n bilinear subdivision, wound so its geometric normal points along
// `facing` (one-sided emitters and consistent normals need this).
void addQuad(MeshBuilder& b, Quad q, int n, Vec3f facing) {
  Vec3f normal = cross(q[1] - q[0], q[3] - q[0]);
  if (dot(normal, facing) < 0) std::swap(q[1], q[3]);
  const int32_t first = b.vertexCount();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      float u = float(i) / float(n), v = float(j) / float(n);
      b.vertex(lerp(lerp(q[0], q[1], u), lerp(q[3], q[2], u), v));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int32_t v00 = first + j * (n + 1) + i, v01 = v00 + (n + 1);
      b.quad(v00, v00 + 1, v01 + 1, v01);
    }
}

MeshCounts quadCounts(int n) {
  return gridCounts(n, n);
}

}  // namespace

ScenePlan planCornell(double scale, uint32_t /*seed: the box has no randomness*/) {
  ScenePlan plan;
  plan.name = "cornell";
  const int n = int(std::clamp(std::round(scale), 1.0, 4096.0));

  auto diffuse = [&](const char* name, Vec3f colour) {
    Material m;
    m.name = name;
    m.baseColor = colour;
    return plan.addMaterial(m);
  };
  // Reflectances as commonly used with this geometry (Mitsuba's and pbrt's scenes).
  const int32_t white = diffuse("white", {0.725f, 0.71f, 0.68f});
  const int32_t red = diffuse("red", {0.63f, 0.065f, 0.05f});
  const int32_t green = diffuse("green", {0.14f, 0.45f, 0.091f});
  Material lightMaterial;
  lightMaterial.name = "light";
  lightMaterial.baseColor = {0.78f, 0.78f, 0.78f};
  lightMaterial.emission = {17, 12, 4};
  const int32_t light = plan.addMaterial(lightMaterial);

  auto surface = [&](const char* name, int32_t material, std::vector<Quad> quads,
                     std::function<Vec3f(const Quad&)> facing) {
    MeshRecipe r;
    r.name = name;
    r.material = material;
    r.counts = quadCounts(n) * quads.size();
    r.hasNormals = false;
    r.hasUvs = false;
    r.build = [quads, facing, n, counts = r.counts] {
      MeshBuilder b(false, false, counts);
      for (const Quad& q : quads) addQuad(b, q, n, facing(q));
      return b.finish();
    };
    plan.addSingleInstanceMesh(std::move(r));
  };
  auto inward = [](const Quad& q) { return kBoxCentre - quadCentre(q); };
  auto outwardOf = [](const std::array<Quad, 5>& block) {
    // The block's centre: below the middle of its top face, at half height.
    Vec3f top = quadCentre(block[0]);
    Vec3f centre{top.x, 0.5f * top.y, top.z};
    return [centre](const Quad& q) { return quadCentre(q) - centre; };
  };
  surface("floor", white, {kFloor}, inward);
  surface("ceiling", white, {kCeiling}, inward);
  surface("back-wall", white, {kBackWall}, inward);
  surface("left-wall", red, {kLeftWall}, inward);
  surface("right-wall", green, {kRightWall}, inward);
  surface("short-block", white, {kShortBlock.begin(), kShortBlock.end()}, outwardOf(kShortBlock));
  surface("tall-block", white, {kTallBlock.begin(), kTallBlock.end()}, outwardOf(kTallBlock));
  surface("light", light, {kLight}, [](const Quad&) { return Vec3f(0, -1, 0); });

  plan.environmentColor = {0, 0, 0};
  CameraView view;
  view.name = "default";
  view.from = {278, 273, -800};
  view.at = {278, 273, 0};
  view.fovY = 39.3077f;
  plan.views.push_back(view);

  for (const Quad* q : {&kFloor, &kCeiling, &kBackWall, &kRightWall, &kLeftWall})
    for (const Vec3f& p : *q) plan.bounds.extend(p);
  return plan;
}

}  // namespace ferry::builtin
