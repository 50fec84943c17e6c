// Triangles for pbrt's non-triangle shapes. Ferry traces triangles only (one
// Embree geometry type, one memory model), so quadrics, patches, subdivision
// surfaces and curves are turned into triangle meshes when loaded. All in the
// shape's own space; errors are InputErrors without a location (the caller
// adds the directive's).
#pragma once

#include <cstdint>
#include <vector>

#include "scene/scene.h"
#include "shapes/curves.h"

namespace ferry {

// Angular resolution of the quadrics: 64 segments for a full turn.
constexpr int kQuadricSegments = 64;

// pbrt's sphere: radius, the part between zmin and zmax (clamped to the
// radius) and between 0 and phiMax degrees around z. Normals point outwards;
// uv = (phi / phiMax, (theta - thetaMin) / (thetaMax - thetaMin)).
Mesh tessellateSphere(float radius, float zMin, float zMax, float phiMaxDegrees,
                      int segments = kQuadricSegments);
// A disk (annulus when innerRadius > 0) at z = height, normal +z.
Mesh tessellateDisk(float height, float radius, float innerRadius, float phiMaxDegrees,
                    int segments = kQuadricSegments);
// An open cylinder around z from zMin to zMax.
Mesh tessellateCylinder(float radius, float zMin, float zMax, float phiMaxDegrees,
                        int segments = kQuadricSegments);
// pbrt-v3's cone: radius at z = 0 narrowing to a point at z = height.
Mesh tessellateCone(float radius, float height, float phiMaxDegrees,
                    int segments = kQuadricSegments);
// pbrt-v3's paraboloid: z = zMax (x^2 + y^2) / radius^2, between zMin and zMax.
Mesh tessellateParaboloid(float radius, float zMin, float zMax, float phiMaxDegrees,
                          int segments = kQuadricSegments);
// pbrt-v3's hyperboloid: the segment from p1 to p2 swept around z.
Mesh tessellateHyperboloid(Vec3f p1, Vec3f p2, float phiMaxDegrees,
                           int segments = kQuadricSegments);
// (All three: uv = (phi / phiMax, v along the profile), normals as pbrt's,
// cross(dp/du, dp/dv).)
// pbrt-v3's heightfield: nu x nv heights over the unit square.
Mesh tessellateHeightfield(int nu, int nv, const std::vector<float>& heights);

// pbrt-v4's bilinear patches: four vertices each (p00 p10 p01 p11). A planar
// patch becomes two triangles on its own vertices; a curved one an 8x8 grid
// of the bilinear surface. `uvs` and `normals` are empty or one per position.
Mesh tessellateBilinearPatches(const std::vector<Vec3f>& positions,
                               const std::vector<int32_t>& indices, const std::vector<Vec2f>& uvs,
                               const std::vector<Vec3f>& normals);

// Loop subdivision, `levels` times, then the vertices moved to their limit
// positions and given area-weighted normals. Boundaries follow the boundary
// rules (creases), non-manifold edges are treated as boundaries.
// The result may not exceed `maxTriangles` (InputError naming the levels).
Mesh loopSubdivide(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& triangles,
                   int levels, uint64_t maxTriangles = uint64_t(1) << 26);

// pbrt's curves: cubic or quadratic, Bézier or uniform B-spline control
// points, as cubic Bézier segments (shapes/curves.h): each segment of the
// curve is cut into 2^splitDepth pieces as pbrt cuts it, with the curve's
// widths interpolated along it and, for ribbons, the normals given at its
// ends (one per segment end).
enum class CurveBasis { Bezier, BSpline };
struct CurveDescription {
  std::vector<Vec3f> points;
  int degree = 3;
  CurveBasis basis = CurveBasis::Bezier;
  CurveType type = CurveType::Flat;
  float width0 = 1, width1 = 1;
  std::vector<Vec3f> normals;  // ribbons only: segments + 1
  int splitDepth = 3;          // pbrt's default
};
// Appends the curve's pieces; InputError if its points, widths or normals
// are not usable. `normals` receives a ribbon's normal pairs.
void appendCurveSegments(const CurveDescription& curve, std::vector<CurveSegment>& segments,
                         std::vector<CurveNormals>& normals);
// Segments the control points make; InputError if the count does not fit the basis and degree.
int curveSegmentCount(const CurveDescription& curve);

// Area-weighted vertex normals from the triangles.
void computeVertexNormals(Mesh& mesh);
// Total surface area.
float meshArea(const Mesh& mesh);
// True when every corner's normal is perpendicular to its triangle (within
// about half a degree): normals that carry no shading information, such as
// N = (0, 1, 0) on a floor in the plane z = 0. A renderer that shades with
// them sees the surface edge-on everywhere (black); callers drop them.
bool normalsPerpendicularToFaces(const Mesh& mesh);

}  // namespace ferry
