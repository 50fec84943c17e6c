// Unstructured volumes (shapes/unstructured_volume.h): a cluster's lookups
// interpolate its cells; transmittance through builtin:tets matches the same
// lattice's values resampled as a structured (trilinear) grid; subsets and
// part-file records cross rays as the whole does.
#include "shapes/unstructured_volume.h"

#include <gtest/gtest.h>

#include <cmath>

#include "builtin/tets.h"
#include "core/error.h"
#include "core/record.h"
#include "io/scene_loader.h"
#include "render/render_test_util.h"
#include "scene/scene.h"

namespace ferry {
namespace {

std::shared_ptr<const UnstructuredVolume> tets(const Scene& scene) {
  for (const Geometry& g : scene.geometries)
    if (auto v = std::dynamic_pointer_cast<const UnstructuredVolume>(g.shape)) return v;
  return nullptr;
}

// One tetrahedron: its value is interpolated linearly, 0 outside.
TEST(UnstructuredVolume, ACellInterpolatesItsPoints) {
  auto v = UnstructuredVolume::make(
      {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0.0f, 1.0f, 0.5f, 0.25f}, {{0, 1, 2, 3}},
      std::make_shared<TransferFunction>(TransferFunction::standard()));
  float value = -1;
  ASSERT_TRUE(v->valueAt(0, {0.25f, 0.25f, 0.25f}, value));
  EXPECT_NEAR(value, 0.25f * 1 + 0.25f * 0.5f + 0.25f * 0.25f, 1e-6f);
  EXPECT_FALSE(v->valueAt(0, {0.6f, 0.6f, 0.1f}, value));
  EXPECT_EQ(v->primitiveCount(), 1u);
  EXPECT_THROW(
      UnstructuredVolume::make({{0, 0, 0}}, {0.5f}, {{0, 1, 2, 3}},
                               std::make_shared<TransferFunction>(TransferFunction::standard())),
      InputError);
}

// Transmittance along rays through the ball's rim: exp(-integral) of the
// cells' field within 1 % of the same lattice values looked up trilinearly
// (a structured grid of them); and the fraction of rays (each origin
// nudged, so each its own random numbers) that meet no collision in any
// cluster within 4 standard errors of it.
TEST(UnstructuredVolume, TransmittanceMatchesAStructuredResampling) {
  const uint32_t n = builtin::tetsCubesPerSide(384000);
  const Scene scene = loadScene("builtin:tets?count=384000");
  const auto v = tets(scene);
  ASSERT_NE(v, nullptr);
  const TransferFunction tf = [] {
    TransferFunction t = TransferFunction::standard();
    return t.withScale(t.scale() / 2);
  }();
  auto structured = [&](Vec3f p) {  // trilinear over the lattice's points
    float f[3];
    int i[3];
    for (int a = 0; a < 3; ++a) {
      const float x = std::clamp((p[a] + 1) * 0.5f * float(n), 0.0f, float(n) - 1e-4f);
      i[a] = int(x);
      f[a] = x - float(i[a]);
    }
    float sum = 0;
    for (int c = 0; c < 8; ++c) {
      float w = 1;
      Vec3f q;
      for (int a = 0; a < 3; ++a) {
        const int bit = (c >> a) & 1;
        w *= bit ? f[a] : 1 - f[a];
        q[a] = float(i[a] + bit) * 2.0f / float(n) - 1;
      }
      sum += w * builtin::tetsField(q);
    }
    return sum;
  };
  const Vec3f directions[] = {normalize(Vec3f(1, 0.1f, 0.05f)), normalize(Vec3f(0.3f, 1, -0.2f)),
                              normalize(Vec3f(-0.4f, 0.2f, 1))};
  // Through the ball's rim, where the transmittance is neither 0 nor 1.
  const Vec3f offsets[] = {{0, 0.7f, 0.2f}, {0.75f, 0.05f, 0.1f}, {0.15f, -0.72f, 0.1f}};
  for (int r = 0; r < 3; ++r) {
    const Vec3f d = directions[r], start = offsets[r] - d * 1.8f;
    // exp(-integral of sigma) over [0, 3.6] by the midpoint rule.
    double optical = 0;
    const int steps = 20000;
    for (int k = 0; k < steps; ++k) {
      const Vec3f p = start + d * (3.6f * (float(k) + 0.5f) / float(steps));
      optical += tf.scale() * tf.opacity(structured(p)) * (3.6 / steps);
    }
    const double expected = std::exp(-optical);
    std::vector<uint32_t> crossed;
    for (uint32_t c = 0; c < v->primitiveCount(); ++c) {
      Box3f b = v->primitiveBounds(c);
      b.lower = b.lower - Vec3f(0.01f);
      b.upper = b.upper + Vec3f(0.01f);
      float t0 = 0, t1 = 3.6f;
      bool hit = true;
      for (int a = 0; a < 3 && hit; ++a) {
        float tn = (b.lower[a] - start[a]) / d[a], tf2 = (b.upper[a] - start[a]) / d[a];
        if (tn > tf2) std::swap(tn, tf2);
        t0 = std::max(t0, tn);
        t1 = std::min(t1, tf2);
        hit = t0 <= t1;
      }
      if (hit) crossed.push_back(c);
    }
    const int rays = 40000;
    int passed = 0;
    for (int k = 0; k < rays; ++k) {
      const Vec3f o = start - d * (1e-5f * float(k));
      const float tEnd = 3.6f + 1e-5f * float(k);
      bool hit = false;
      for (uint32_t c : crossed) {
        float t;
        Vec2f uv;
        if (v->intersect(c, o, d, 0, tEnd, t, uv)) {
          hit = true;
          break;
        }
      }
      passed += !hit;
    }
    const double measured = double(passed) / rays;
    double opticalTets = 0;
    for (int k = 0; k < steps; ++k) {
      const Vec3f p = start + d * (3.6f * (float(k) + 0.5f) / float(steps));
      float value = 0;
      for (uint32_t c : crossed)
        if (v->valueAt(c, p, value)) break;
      opticalTets += tf.scale() * tf.opacity(value) * (3.6 / steps);
    }

    // The field itself: its transmittance against the structured grid's, to 1 %.
    const double exact = std::exp(-opticalTets);
    EXPECT_NEAR(exact / expected, 1.0, 0.01)
        << "ray " << r << ": " << exact << " against " << expected;
    // Tracking is unbiased: the fraction that passed, within 4 standard errors.
    const double sigma = std::sqrt(exact * (1 - exact) / rays);
    EXPECT_NEAR(measured, exact, 4 * sigma) << "ray " << r;
  }
}

// A subset of clusters, and a shape read back from its record, answer every
// ray as the whole does for those clusters.
TEST(UnstructuredVolume, SubsetsAndRecordsCrossAsTheWhole) {
  const Scene scene = loadScene("builtin:tets?count=6000");
  const auto v = tets(scene);
  ASSERT_NE(v, nullptr);
  const std::vector<uint32_t> some = {3, 17, 40, 41, 2};
  const auto part = v->subset(some);
  RecordWriter writer;
  v->write(writer);
  RecordReader reader(writer.bytes(), "test");
  const auto back = UnstructuredVolume::read(reader);
  ASSERT_EQ(part->primitiveCount(), some.size());
  ASSERT_EQ(back->primitiveCount(), v->primitiveCount());
  testing::TestRng rng(7);
  int hits = 0;
  for (int k = 0; k < 4000; ++k) {
    const Vec3f o{2 * rng.uniform() - 1, 2 * rng.uniform() - 1, -2};
    const Vec3f d =
        normalize(Vec3f(0.4f * (rng.uniform() - 0.5f), 0.4f * (rng.uniform() - 0.5f), 1));
    for (size_t i = 0; i < some.size(); ++i) {
      float ta = -1, tb = -1, tc = -1;
      Vec2f uv;
      const bool a = v->intersect(some[i], o, d, 0, kInfinity, ta, uv);
      EXPECT_EQ(a, part->intersect(uint32_t(i), o, d, 0, kInfinity, tb, uv));
      EXPECT_EQ(a, back->intersect(some[i], o, d, 0, kInfinity, tc, uv));
      EXPECT_EQ(ta, tb);
      EXPECT_EQ(ta, tc);
      EXPECT_EQ(v->primitiveBounds(some[i]).lower, part->primitiveBounds(uint32_t(i)).lower);
      hits += a;
    }
  }
  EXPECT_GT(hits, 20);
}

// A restyle scales the majorants with the opacity; undone, the volume
// answers every ray as before.
TEST(UnstructuredVolume, RestylingKeepsTheCellsAndMovesTheMajorants) {
  const Scene scene = loadScene("builtin:tets?count=6000");
  const auto v = std::const_pointer_cast<UnstructuredVolume>(tets(scene));
  ASSERT_NE(v, nullptr);
  const auto loaded = v->transfer();
  const auto copy = v->subset(std::vector<uint32_t>{10, 11, 12});
  std::vector<float> before;
  for (uint32_t c = 0; c < v->primitiveCount(); ++c) before.push_back(v->majorant(c));
  v->restyle(std::make_shared<const TransferFunction>(loaded->withScale(loaded->scale() * 4)));
  for (uint32_t c = 0; c < v->primitiveCount(); ++c)
    EXPECT_FLOAT_EQ(v->majorant(c), 4 * before[c]) << c;
  v->restyle(loaded);
  testing::TestRng rng(3);
  for (int k = 0; k < 2000; ++k) {
    const Vec3f o{2 * rng.uniform() - 1, 2 * rng.uniform() - 1, -2};
    const Vec3f d =
        normalize(Vec3f(0.3f * (rng.uniform() - 0.5f), 0.3f * (rng.uniform() - 0.5f), 1));
    for (uint32_t i = 0; i < 3; ++i) {
      float ta = -1, tb = -1;
      Vec2f uv;
      EXPECT_EQ(v->intersect(10 + i, o, d, 0, kInfinity, ta, uv),
                copy->intersect(i, o, d, 0, kInfinity, tb, uv));
      EXPECT_EQ(ta, tb);
    }
  }
}

}  // namespace
}  // namespace ferry
