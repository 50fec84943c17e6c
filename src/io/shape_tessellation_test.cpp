#include "io/shape_tessellation.h"

#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "core/error.h"

namespace ferry {
namespace {

// Every edge shared by exactly two triangles: a closed surface.
bool closed(const Mesh& m) {
  std::map<std::pair<int, int>, int> edges;
  for (const Vec3i& t : m.indices)
    for (int k = 0; k < 3; ++k) {
      int a = t[k], b = t[(k + 1) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  for (const auto& [e, n] : edges)
    if (n != 2) return false;
  return true;
}

TEST(ShapeTessellation, SphereAreaAndNormals) {
  Mesh s = tessellateSphere(2, -2, 2, 360);
  EXPECT_NEAR(meshArea(s), 4 * kPi * 4, 0.02 * 4 * kPi * 4);
  ASSERT_EQ(s.normals.size(), s.positions.size());
  for (size_t i = 0; i < s.positions.size(); ++i) {
    EXPECT_NEAR(length(s.positions[i]), 2, 1e-5);
    EXPECT_NEAR(dot(s.normals[i], s.positions[i] / 2), 1, 1e-5);
  }
  // A hemisphere has half the area.
  EXPECT_NEAR(meshArea(tessellateSphere(2, 0, 2, 360)), 0.5 * meshArea(s), 0.02 * meshArea(s));
  EXPECT_THROW(tessellateSphere(0, -1, 1, 360), InputError);
  EXPECT_THROW(tessellateSphere(NAN, -1, 1, 360), InputError);
}

TEST(ShapeTessellation, DiskAnnulusAndCylinder) {
  EXPECT_NEAR(meshArea(tessellateDisk(1, 1, 0, 360)), kPi, 0.01 * kPi);
  EXPECT_NEAR(meshArea(tessellateDisk(0, 2, 1, 360)), kPi * 3, 0.01 * kPi * 3);
  EXPECT_NEAR(meshArea(tessellateDisk(0, 1, 0, 180)), kPi / 2, 0.01 * kPi);
  Mesh d = tessellateDisk(3, 1, 0, 360);
  EXPECT_EQ(d.bounds().lower.z, 3);
  EXPECT_NEAR(meshArea(tessellateCylinder(1, 0, 2, 360)), 2 * kPi * 2, 0.01 * 4 * kPi);
}

TEST(ShapeTessellation, LoopSubdivisionOfATetrahedron) {
  std::vector<Vec3f> p = {{1, 1, 1}, {-1, -1, 1}, {-1, 1, -1}, {1, -1, -1}};
  std::vector<Vec3i> t = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  Mesh m = loopSubdivide(p, t, 3);
  EXPECT_EQ(m.triangleCount(), 4u * 64u);
  // Euler: V - E + F = 2 with E = 3F/2.
  EXPECT_EQ(m.vertexCount(), 2 + m.triangleCount() / 2);
  EXPECT_TRUE(closed(m));
  // The limit surface shrinks inside the control hull, towards a sphere-like blob.
  float r0 = length(p[0]);
  for (const Vec3f& v : m.positions) EXPECT_LT(length(v), r0);
  EXPECT_EQ(m.normals.size(), m.vertexCount());
  EXPECT_THROW(loopSubdivide(p, t, 20, uint64_t(1) << 20), InputError);
  std::vector<Vec3i> bad = {{0, 1, 9}};
  EXPECT_THROW(loopSubdivide(p, bad, 1), InputError);
}

TEST(ShapeTessellation, LoopSubdivisionKeepsBoundaries) {
  // A single triangle: boundary rules only; corners stay put.
  std::vector<Vec3f> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  Mesh m = loopSubdivide(p, {{0, 1, 2}}, 2);
  EXPECT_EQ(m.triangleCount(), 16u);
  for (const Vec3f& v : m.positions) EXPECT_EQ(v.z, 0);
}

TEST(ShapeTessellation, BilinearPatches) {
  std::vector<Vec3f> flat = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  Mesh f = tessellateBilinearPatches(flat, {0, 1, 2, 3}, {}, {});
  EXPECT_EQ(f.triangleCount(), 2u);
  EXPECT_NEAR(meshArea(f), 1, 1e-6);
  std::vector<Vec3f> saddle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}};
  Mesh s = tessellateBilinearPatches(saddle, {0, 1, 2, 3}, {{0, 0}, {1, 0}, {0, 1}, {1, 1}}, {});
  EXPECT_EQ(s.triangleCount(), 128u);
  // Points of the saddle z = u v.
  for (size_t i = 4; i < s.positions.size(); ++i)
    EXPECT_NEAR(s.positions[i].z, s.positions[i].x * s.positions[i].y, 1e-5);
  EXPECT_THROW(tessellateBilinearPatches(flat, {0, 1, 2}, {}, {}), InputError);
  EXPECT_THROW(tessellateBilinearPatches(flat, {0, 1, 2, 7}, {}, {}), InputError);
}

TEST(ShapeTessellation, CurvesBecomePbrtsBezierPieces) {
  CurveDescription c;
  c.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  c.width0 = 0.1f;
  c.width1 = 0.3f;
  std::vector<CurveSegment> segments;
  std::vector<CurveNormals> normals;
  appendCurveSegments(c, segments, normals);
  ASSERT_EQ(segments.size(), 8u);  // pbrt's splitdepth 3
  EXPECT_TRUE(normals.empty());
  // The pieces join end to end; the widths are interpolated along the curve.
  for (size_t k = 0; k < segments.size(); ++k) {
    EXPECT_NEAR(segments[k].points[0].x, 3.0f * float(k) / 8, 1e-5);
    EXPECT_NEAR(segments[k].points[3].x, 3.0f * float(k + 1) / 8, 1e-5);
    EXPECT_NEAR(segments[k].width0, 0.1f + 0.2f * float(k) / 8, 1e-6);
    EXPECT_FLOAT_EQ(segments[k].u0, float(k) / 8);
  }
  // A second curve appends.
  appendCurveSegments(c, segments, normals);
  EXPECT_EQ(segments.size(), 16u);

  CurveDescription spline = c;
  spline.basis = CurveBasis::BSpline;
  spline.points.push_back({4, 0, 0});  // 5 points: 2 segments
  EXPECT_EQ(curveSegmentCount(spline), 2);
  CurveDescription ribbon = c;
  ribbon.type = CurveType::Ribbon;
  ribbon.splitDepth = 0;
  ribbon.normals = {{0, 0, 1}, {0, 1, 0}};
  std::vector<CurveSegment> r;
  appendCurveSegments(ribbon, r, normals);
  ASSERT_EQ(r.size(), 1u);
  ASSERT_EQ(normals.size(), 1u);
  EXPECT_EQ(normals[0][1], Vec3f(0, 1, 0));
  ribbon.normals.pop_back();
  EXPECT_THROW(appendCurveSegments(ribbon, r, normals), InputError);
  c.points.pop_back();
  EXPECT_THROW(appendCurveSegments(c, r, normals), InputError);
  c.degree = 5;
  EXPECT_THROW(curveSegmentCount(c), InputError);
}

TEST(ShapeTessellation, PerpendicularNormals) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.indices = {{0, 1, 2}};
  m.normals = {{0, 1, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_TRUE(normalsPerpendicularToFaces(m));
  m.normals[2] = {0, 0.2f, 1};
  EXPECT_FALSE(normalsPerpendicularToFaces(m));
}

}  // namespace
}  // namespace ferry
