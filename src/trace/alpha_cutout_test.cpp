// Cut-outs in both backends, through instances and at the top level: solid
// alpha textures evaluated at the hit's world point; each alpha test (below
// a cutoff, zero, stochastic) and the rays each cut-out names.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "render/render_test_util.h"
#include "scene/scene.h"
#include "trace/embree_backend.h"
#include "trace/reference_backend.h"

namespace ferry {
namespace {

using testing::diffuseMaterial;
using testing::makeQuad;

// Three copies of one 4 x 4 square in the plane z = 0 (its object space),
// cut out by an fBm of frequency 2 in world space at cutoff 0: one placed
// alone at the top level (x in [-6, -2]), two through instances of one
// object, moved to x in [-2, 2] and lifted to z = 1 with a quarter turn
// (x in [2, 6]). fBm is negative about half the time, so each copy is
// about half holes, and the copies' holes differ because their world
// points do.
struct Cutouts {
  Scene scene;
  SolidTexture fbm;
  float cutoff = 0;
};

Cutouts cutoutScene() {
  Cutouts c;
  c.fbm.kind = SolidTextureKind::Fbm;
  c.fbm.octaves = 4;
  c.fbm.worldToTexture = Affine3f::scale(Vec3f(2));
  Texture texture;
  texture.name = "fbm";
  texture.solid = c.fbm;
  c.scene.textures.push_back(texture);
  Material m = diffuseMaterial(Vec3f(0.5f));
  m.alphaTexture = 0;
  m.alphaCutoff = c.cutoff;
  const int32_t material = c.scene.addMaterial(m);
  c.scene.addSingleInstanceMesh(makeQuad({-6, -2, 0}, {4, 0, 0}, {0, 4, 0}, material));
  const int32_t shared =
      c.scene.addSingleInstanceMesh(makeQuad({-2, -2, 0}, {4, 0, 0}, {0, 4, 0}, material));
  c.scene.instances.push_back(
      {shared, Affine3f::translate({4, 0, 1}) * Affine3f::rotate({0, 0, 1}, float(M_PI / 2))});
  return c;
}

// The world point's expected answer: a hole, a hit, or too near the cutoff
// to say (the backends interpolate the point in float, each its own way).
enum class Expect { Hole, Hit, Either };
Expect expected(const Cutouts& c, Vec3f world) {
  const Vec3f v = c.fbm.evaluate(world);
  const float alpha = (v.x + v.y + v.z) / 3;
  if (std::abs(alpha - c.cutoff) < 1e-3f) return Expect::Either;
  return alpha < c.cutoff ? Expect::Hole : Expect::Hit;
}

void expectSolidHoles(const std::string& name, const TraceBackend& backend, const Cutouts& c) {
  constexpr int kSide = 96;
  int holes[3] = {}, hits[3] = {}, wrong = 0, samePattern = 0, compared = 0;
  for (int copy = 0; copy < 3; ++copy)
    for (int j = 0; j < kSide; ++j)
      for (int i = 0; i < kSide; ++i) {
        // A point inside the copy's square, seen from above along -z.
        const Vec3f world{-6 + 4.0f * copy + 4 * (i + 0.5f) / kSide, -2 + 4 * (j + 0.5f) / kSide,
                          copy == 2 ? 1.0f : 0.0f};
        const TraceRay ray{world + Vec3f{0, 0, 5}, {0, 0, -1}, 0, 10};
        const TraceHit hit = backend.intersect(ray);
        const bool blocked = backend.occluded(ray);
        EXPECT_EQ(hit.valid(), blocked) << name << " at " << world.x << ", " << world.y;
        const Expect e = expected(c, world);
        if (e == Expect::Either) continue;
        (hit.valid() ? hits : holes)[copy]++;
        wrong += hit.valid() != (e == Expect::Hit);
        if (hit.valid()) {
          EXPECT_NEAR(hit.t, 5, 1e-4f) << name;
        }
        if (copy == 2) {  // what the object-space point would have said
          const Expect local =
              expected(c, c.scene.instances.back().transform.inverse().transformPoint(world));
          if (local != Expect::Either) {
            ++compared;
            samePattern += local == e;
          }
        }
      }
  EXPECT_EQ(wrong, 0) << name;
  for (int copy = 0; copy < 3; ++copy) {
    const double share = double(holes[copy]) / (holes[copy] + hits[copy]);
    EXPECT_GT(share, 0.25) << name << " copy " << copy;
    EXPECT_LT(share, 0.75) << name << " copy " << copy;
  }
  // World space, not object space: the moved instance's holes are not those
  // of its object's points.
  EXPECT_GT(compared, kSide * kSide / 2) << name;
  EXPECT_LT(samePattern, compared * 0.8) << name;
}

TEST(AlphaCutout, SolidTexturesCutHolesAtTheWorldPointInBothBackends) {
  const Cutouts c = cutoutScene();
  ASSERT_NO_THROW(c.scene.validate());
  expectSolidHoles("embree shared", *makeEmbreeBackend(c.scene, {}, Instancing::Shared), c);
  expectSolidHoles("embree always", *makeEmbreeBackend(c.scene, {}, Instancing::Always), c);
  expectSolidHoles("reference shared", *makeReferenceBackend(c.scene, {}, Instancing::Shared), c);
  expectSolidHoles("reference always", *makeReferenceBackend(c.scene, {}, Instancing::Always), c);
}

// Two squares (z = 1 and z = 0, x and y in [-2, 2]), both cut out by a
// constant alpha under `test`, cutting `rays`; the lower one placed twice
// (the second far away), so it goes through an instance.
Scene stackedSquares(float alpha, AlphaTest test, AlphaRays rays) {
  Scene scene;
  Texture constant;
  constant.name = "alpha";
  constant.width = constant.height = 1;
  constant.srgb = false;
  constant.rgba = {255, 255, 255, uint8_t(std::lround(alpha * 255))};
  scene.textures.push_back(constant);
  Material m = diffuseMaterial(Vec3f(0.5f));
  m.alphaTexture = 0;
  m.alphaTest = test;
  m.alphaRays = rays;
  const int32_t material = scene.addMaterial(m);
  scene.addSingleInstanceMesh(makeQuad({-2, -2, 1}, {4, 0, 0}, {0, 4, 0}, material));
  const int32_t lower =
      scene.addSingleInstanceMesh(makeQuad({-2, -2, 0}, {4, 0, 0}, {0, 4, 0}, material));
  scene.instances.push_back({lower, Affine3f::translate({100, 0, 0})});
  return scene;
}

// What rays from above find on the stacked squares, in both backends and
// both instancing modes, which must agree ray for ray: the share of paths
// stopped by the upper square, by the lower one, and of shadow rays stopped.
struct Stops {
  double upper = 0, lower = 0, shadowed = 0;
};
Stops stops(const Scene& scene) {
  constexpr int kSide = 96;
  const std::unique_ptr<TraceBackend> backends[] = {
      makeEmbreeBackend(scene, {}, Instancing::Shared),
      makeEmbreeBackend(scene, {}, Instancing::Always),
      makeReferenceBackend(scene, {}, Instancing::Shared),
      makeReferenceBackend(scene, {}, Instancing::Always)};
  Stops s;
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) {
      const Vec3f origin{-1.8f + 3.6f * (i + 0.5f) / kSide, -1.8f + 3.6f * (j + 0.5f) / kSide, 5};
      // Slightly slanted, so no two rays are alike.
      const TraceRay ray{origin, normalize(Vec3f{0.01f * (j - i) / kSide, 0.02f, -1}), 0, 10};
      const TraceHit first = backends[0]->intersect(ray);
      const bool blocked = backends[0]->occluded(ray);
      for (const auto& b : backends) {
        const TraceHit hit = b->intersect(ray);
        EXPECT_EQ(hit.valid(), first.valid());
        if (hit.valid() && first.valid()) {
          EXPECT_NEAR(hit.t, first.t, 1e-4f);
        }
        EXPECT_EQ(b->occluded(ray), blocked);
      }
      if (first.valid()) (first.t < 4.5f ? s.upper : s.lower) += 1;
      s.shadowed += blocked;
    }
  s.upper /= kSide * kSide;
  s.lower /= kSide * kSide;
  s.shadowed /= kSide * kSide;
  return s;
}

TEST(AlphaCutout, StochasticCutOutsPassRaysWithProbabilityOneMinusAlpha) {
  // Each square stops a ray with probability 0.3, independently of the other.
  const Stops s = stops(stackedSquares(0.3f, AlphaTest::Stochastic, AlphaRays::All));
  EXPECT_NEAR(s.upper, 0.3, 0.03);
  EXPECT_NEAR(s.lower, 0.7 * 0.3, 0.03);
  EXPECT_NEAR(s.shadowed, 1 - 0.7 * 0.7, 0.03);
  // Alpha 1 stops every ray, alpha 0 none.
  EXPECT_EQ(stops(stackedSquares(1, AlphaTest::Stochastic, AlphaRays::All)).upper, 1.0);
  const Stops none = stops(stackedSquares(0, AlphaTest::Stochastic, AlphaRays::All));
  EXPECT_EQ(none.upper + none.lower + none.shadowed, 0.0);
}

TEST(AlphaCutout, ZeroCutsOnlyWhereAlphaIsZeroAndBelowAtTheCutoff) {
  EXPECT_EQ(stops(stackedSquares(0.3f, AlphaTest::Zero, AlphaRays::All)).upper, 1.0);
  const Stops zero = stops(stackedSquares(0, AlphaTest::Zero, AlphaRays::All));
  EXPECT_EQ(zero.upper + zero.lower + zero.shadowed, 0.0);
  const Stops below = stops(stackedSquares(0.3f, AlphaTest::Below, AlphaRays::All));
  EXPECT_EQ(below.upper + below.lower + below.shadowed, 0.0);
  EXPECT_EQ(stops(stackedSquares(0.7f, AlphaTest::Below, AlphaRays::All)).upper, 1.0);
}

TEST(AlphaCutout, ACutOutCutsOnlyTheRaysItNames) {
  const Stops paths = stops(stackedSquares(0, AlphaTest::Zero, AlphaRays::NotShadowRays));
  EXPECT_EQ(paths.upper + paths.lower, 0.0);
  EXPECT_EQ(paths.shadowed, 1.0);
  const Stops shadows = stops(stackedSquares(0, AlphaTest::Zero, AlphaRays::ShadowRaysOnly));
  EXPECT_EQ(shadows.upper, 1.0);
  EXPECT_EQ(shadows.shadowed, 0.0);
}

}  // namespace
}  // namespace ferry
