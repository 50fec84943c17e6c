#include "io/shape_tessellation.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {
namespace {

float radians(float degrees) {
  return degrees * kPi / 180.0f;
}

int segmentsFor(float phiMax, int fullTurn) {
  return std::max(3, int(std::ceil(std::max(fullTurn, 3) * phiMax / (2 * kPi))));
}

float clampedPhiMax(float degrees) {
  return radians(std::clamp(degrees, 0.0f, 360.0f));
}

void checkFinite(float v, const char* what) {
  if (!std::isfinite(v)) throw InputError(fmt::format("{} is not finite", what));
}

// Quads of a (rows+1) x (cols+1) vertex grid, two triangles each.
void gridTriangles(Mesh& m, int rows, int cols, int32_t first = 0) {
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      int32_t a = first + r * (cols + 1) + c, b = a + 1, d = a + (cols + 1), e = d + 1;
      m.indices.push_back({a, b, e});
      m.indices.push_back({a, e, d});
    }
}

}  // namespace

Mesh tessellateSphere(float radius, float zMin, float zMax, float phiMaxDegrees, int segments) {
  checkFinite(radius, "sphere radius");
  checkFinite(zMin, "sphere zmin");
  checkFinite(zMax, "sphere zmax");
  if (!(radius > 0)) throw InputError(fmt::format("sphere radius {} must be positive", radius));
  float z0 = std::clamp(std::min(zMin, zMax), -radius, radius);
  float z1 = std::clamp(std::max(zMin, zMax), -radius, radius);
  float thetaMin = std::acos(std::clamp(z1 / radius, -1.0f, 1.0f));  // from +z
  float thetaMax = std::acos(std::clamp(z0 / radius, -1.0f, 1.0f));
  float phiMax = clampedPhiMax(phiMaxDegrees);
  Mesh m;
  if (!(thetaMax > thetaMin) || !(phiMax > 0)) return m;
  int cols = segmentsFor(phiMax, segments);
  int rows = std::max(2, int(std::ceil(cols / 2.0f * (thetaMax - thetaMin) / kPi)));
  for (int r = 0; r <= rows; ++r) {
    float v = float(r) / rows;
    float theta = thetaMin + v * (thetaMax - thetaMin);
    for (int c = 0; c <= cols; ++c) {
      float u = float(c) / cols;
      float phi = u * phiMax;
      Vec3f n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      m.positions.push_back(n * radius);
      m.normals.push_back(n);
      m.uvs.push_back({u, v});
    }
  }
  // Rows at a pole collapse to a point: one triangle per quad there.
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      int32_t a = r * (cols + 1) + c, b = a + 1, d = a + (cols + 1), e = d + 1;
      bool topPole = r == 0 && thetaMin <= 0;
      bool bottomPole = r == rows - 1 && thetaMax >= kPi;
      if (!topPole) m.indices.push_back({a, e, b});
      if (!bottomPole) m.indices.push_back({a, d, e});
    }
  return m;
}

Mesh tessellateDisk(float height, float radius, float innerRadius, float phiMaxDegrees,
                    int segments) {
  checkFinite(height, "disk height");
  checkFinite(radius, "disk radius");
  checkFinite(innerRadius, "disk innerradius");
  float phiMax = clampedPhiMax(phiMaxDegrees);
  float ri = std::max(0.0f, innerRadius);
  Mesh m;
  if (!(radius > ri) || !(phiMax > 0)) return m;
  int cols = segmentsFor(phiMax, segments);
  for (int ring = 0; ring < 2; ++ring) {
    float r = ring == 0 ? radius : ri;
    for (int c = 0; c <= cols; ++c) {
      float u = float(c) / cols;
      float phi = u * phiMax;
      m.positions.push_back({r * std::cos(phi), r * std::sin(phi), height});
      m.normals.push_back({0, 0, 1});
      m.uvs.push_back({u, float(ring)});
    }
  }
  for (int c = 0; c < cols; ++c) {
    int32_t a = c, b = c + 1, d = cols + 1 + c, e = d + 1;
    m.indices.push_back({a, b, e});
    if (ri > 0) m.indices.push_back({a, e, d});
  }
  return m;
}

Mesh tessellateCylinder(float radius, float zMin, float zMax, float phiMaxDegrees, int segments) {
  checkFinite(radius, "cylinder radius");
  checkFinite(zMin, "cylinder zmin");
  checkFinite(zMax, "cylinder zmax");
  float phiMax = clampedPhiMax(phiMaxDegrees);
  Mesh m;
  if (!(radius > 0) || zMin == zMax || !(phiMax > 0)) return m;
  int cols = segmentsFor(phiMax, segments);
  for (int r = 0; r <= 1; ++r)
    for (int c = 0; c <= cols; ++c) {
      float u = float(c) / cols;
      float phi = u * phiMax;
      Vec3f n(std::cos(phi), std::sin(phi), 0);
      m.positions.push_back({radius * n.x, radius * n.y, r == 0 ? zMin : zMax});
      m.normals.push_back(n);
      m.uvs.push_back({u, float(r)});
    }
  gridTriangles(m, 1, cols);
  return m;
}

namespace {

// A surface of revolution: profile(v) for v in [0, 1] swept by phi in
// [0, phiMax] around z, `rows` steps along the profile. Normals are
// cross(dp/du, dp/dv), by central differences of the profile.
template <typename Profile>
Mesh revolved(float phiMax, int segments, int rows, Profile&& profile) {
  Mesh m;
  if (!(phiMax > 0)) return m;
  const int cols = segmentsFor(phiMax, segments);
  for (int r = 0; r <= rows; ++r) {
    const float v = float(r) / rows;
    const float h = 1e-3f;
    const Vec3f p = profile(v);
    const Vec3f dv = profile(std::min(v + h, 1.0f)) - profile(std::max(v - h, 0.0f));
    for (int c = 0; c <= cols; ++c) {
      const float u = float(c) / cols;
      const float cs = std::cos(u * phiMax), sn = std::sin(u * phiMax);
      auto rotate = [&](Vec3f q) { return Vec3f(cs * q.x - sn * q.y, sn * q.x + cs * q.y, q.z); };
      const Vec3f position = rotate(p);
      const Vec3f dpdu(-position.y, position.x, 0);
      Vec3f n = cross(dpdu, rotate(dv));
      if (!(dot(n, n) > 0)) n = cross(rotate(Vec3f(-p.y, p.x, 0) + Vec3f(0, 1e-6f, 0)), rotate(dv));
      m.positions.push_back(position);
      m.normals.push_back(dot(n, n) > 0 ? normalize(n) : Vec3f(0, 0, 1));
      m.uvs.push_back({u, v});
    }
  }
  gridTriangles(m, rows, cols);
  return m;
}

}  // namespace

Mesh tessellateCone(float radius, float height, float phiMaxDegrees, int segments) {
  checkFinite(radius, "cone radius");
  checkFinite(height, "cone height");
  if (!(radius > 0) || height == 0) return Mesh{};
  return revolved(clampedPhiMax(phiMaxDegrees), segments, 8,
                  [&](float v) { return Vec3f((1 - v) * radius, 0, v * height); });
}

Mesh tessellateParaboloid(float radius, float zMin, float zMax, float phiMaxDegrees, int segments) {
  checkFinite(radius, "paraboloid radius");
  checkFinite(zMin, "paraboloid zmin");
  checkFinite(zMax, "paraboloid zmax");
  const float lo = std::min(zMin, zMax), hi = std::max(zMin, zMax);
  if (!(radius > 0) || !(hi > 0) || lo == hi) return Mesh{};
  const float k = hi / (radius * radius);
  return revolved(clampedPhiMax(phiMaxDegrees), segments, 16, [&](float v) {
    const float z = std::max(lo + v * (hi - lo), 0.0f);
    return Vec3f(std::sqrt(z / k), 0, z);
  });
}

Mesh tessellateHyperboloid(Vec3f p1, Vec3f p2, float phiMaxDegrees, int segments) {
  if (!isFinite(p1) || !isFinite(p2)) throw InputError("hyperboloid p1 or p2 is not finite");
  return revolved(clampedPhiMax(phiMaxDegrees), segments, 8,
                  [&](float v) { return p1 * (1 - v) + p2 * v; });
}

Mesh tessellateHeightfield(int nu, int nv, const std::vector<float>& heights) {
  if (nu < 2 || nv < 2)
    throw InputError(fmt::format("heightfield needs nu, nv >= 2, found {} x {}", nu, nv));
  if (heights.size() != size_t(nu) * size_t(nv))
    throw InputError(fmt::format("heightfield needs nu * nv = {} heights, found {}",
                                 uint64_t(nu) * uint64_t(nv), heights.size()));
  Mesh m;
  m.positions.reserve(heights.size());
  for (int v = 0; v < nv; ++v)
    for (int u = 0; u < nu; ++u) {
      float x = float(u) / (nu - 1), y = float(v) / (nv - 1);
      m.positions.push_back({x, y, heights[size_t(v) * nu + u]});
      m.uvs.push_back({x, y});
    }
  gridTriangles(m, nv - 1, nu - 1);
  computeVertexNormals(m);
  return m;
}

Mesh tessellateBilinearPatches(const std::vector<Vec3f>& positions,
                               const std::vector<int32_t>& indices, const std::vector<Vec2f>& uvs,
                               const std::vector<Vec3f>& normals) {
  if (indices.size() % 4 != 0)
    throw InputError(fmt::format("bilinear patches need 4 indices each, found {}", indices.size()));
  Mesh m;
  m.positions = positions;
  m.uvs = uvs;
  m.normals = normals;
  constexpr int kGrid = 8;
  for (size_t p = 0; p < indices.size(); p += 4) {
    int32_t v[4];
    for (int k = 0; k < 4; ++k) {
      v[k] = indices[p + k];
      if (v[k] < 0 || size_t(v[k]) >= positions.size())
        throw InputError(fmt::format("patch {}: index {} out of range ({} vertices)", p / 4, v[k],
                                     positions.size()));
    }
    Vec3f p00 = positions[v[0]], p10 = positions[v[1]], p01 = positions[v[2]],
          p11 = positions[v[3]];
    Vec3f n = cross(p10 - p00, p01 - p00);
    float size = std::max({length(p10 - p00), length(p01 - p00), length(p11 - p00), 1e-30f});
    float off = length(n) > 0 ? std::abs(dot(p11 - p00, normalize(n))) : 0;
    if (off <= 1e-3f * size) {
      m.indices.push_back({v[0], v[1], v[3]});
      m.indices.push_back({v[0], v[3], v[2]});
      continue;
    }
    // Curved: sample the bilinear surface.
    int32_t first = int32_t(m.positions.size());
    for (int j = 0; j <= kGrid; ++j)
      for (int i = 0; i <= kGrid; ++i) {
        float s = float(i) / kGrid, t = float(j) / kGrid;
        auto bilerp = [&](auto a, auto b, auto c, auto d) {
          return (a * (1 - s) + b * s) * (1 - t) + (c * (1 - s) + d * s) * t;
        };
        m.positions.push_back(bilerp(p00, p10, p01, p11));
        if (!uvs.empty()) m.uvs.push_back(bilerp(uvs[v[0]], uvs[v[1]], uvs[v[2]], uvs[v[3]]));
        if (!normals.empty()) {
          Vec3f nn = bilerp(normals[v[0]], normals[v[1]], normals[v[2]], normals[v[3]]);
          m.normals.push_back(length(nn) > 0 ? normalize(nn) : Vec3f(0, 0, 1));
        }
      }
    gridTriangles(m, kGrid, kGrid, first);
  }
  return m;
}

// ------------------------------------------------------------ loop subdivision

namespace {

struct EdgeInfo {
  int32_t a, b;
  int32_t opposite[2] = {-1, -1};
  int faces = 0;
};

uint64_t edgeKey(int32_t a, int32_t b) {
  if (a > b) std::swap(a, b);
  return (uint64_t(uint32_t(a)) << 32) | uint32_t(b);
}

struct Topology {
  std::vector<EdgeInfo> edges;
  std::vector<int32_t> faceEdges;  // 3 per face: edge of (v0v1, v1v2, v2v0)
  // Per vertex: its neighbours and how many of its edges are boundaries.
  std::vector<std::vector<int32_t>> neighbours;
  std::vector<std::vector<int32_t>> boundaryNeighbours;
};

Topology buildTopology(size_t vertexCount, const std::vector<Vec3i>& tris) {
  Topology t;
  std::unordered_map<uint64_t, int32_t> index;
  index.reserve(tris.size() * 2);
  t.faceEdges.resize(tris.size() * 3);
  for (size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      int32_t a = tris[f][k], b = tris[f][(k + 1) % 3], c = tris[f][(k + 2) % 3];
      auto [it, inserted] = index.try_emplace(edgeKey(a, b), int32_t(t.edges.size()));
      if (inserted) t.edges.push_back({std::min(a, b), std::max(a, b)});
      EdgeInfo& e = t.edges[size_t(it->second)];
      if (e.faces < 2) e.opposite[e.faces] = c;
      ++e.faces;
      t.faceEdges[f * 3 + k] = it->second;
    }
  t.neighbours.resize(vertexCount);
  t.boundaryNeighbours.resize(vertexCount);
  for (const EdgeInfo& e : t.edges) {
    t.neighbours[size_t(e.a)].push_back(e.b);
    t.neighbours[size_t(e.b)].push_back(e.a);
    if (e.faces != 2) {
      t.boundaryNeighbours[size_t(e.a)].push_back(e.b);
      t.boundaryNeighbours[size_t(e.b)].push_back(e.a);
    }
  }
  return t;
}

float loopBeta(size_t valence) {
  return valence == 3 ? 3.0f / 16.0f : 3.0f / (8.0f * float(valence));
}

}  // namespace

Mesh loopSubdivide(const std::vector<Vec3f>& positions, const std::vector<Vec3i>& triangles,
                   int levels, uint64_t maxTriangles) {
  if (levels < 0) throw InputError(fmt::format("subdivision levels {} must be 0 or more", levels));
  if (triangles.empty()) return Mesh{};
  uint64_t final = triangles.size();
  for (int l = 0; l < levels; ++l) {
    final *= 4;
    if (final > maxTriangles)
      throw InputError(
          fmt::format("{} levels of subdivision of {} triangles make more than {} "
                      "triangles",
                      levels, triangles.size(), maxTriangles));
  }
  for (const Vec3i& t : triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || size_t(t[k]) >= positions.size())
        throw InputError(
            fmt::format("index {} out of range ({} vertices)", t[k], positions.size()));
  std::vector<Vec3f> v = positions;
  std::vector<Vec3i> f = triangles;
  for (int level = 0; level < levels; ++level) {
    Topology topo = buildTopology(v.size(), f);
    std::vector<Vec3f> next(v.size() + topo.edges.size());
    // Even vertices.
    for (size_t i = 0; i < v.size(); ++i) {
      const auto& nb = topo.neighbours[i];
      const auto& bn = topo.boundaryNeighbours[i];
      if (nb.empty()) {
        next[i] = v[i];
      } else if (bn.empty()) {
        float beta = loopBeta(nb.size());
        Vec3f sum(0);
        for (int32_t n : nb) sum += v[size_t(n)];
        next[i] = v[i] * (1 - float(nb.size()) * beta) + sum * beta;
      } else if (bn.size() == 2) {
        next[i] = v[i] * 0.75f + (v[size_t(bn[0])] + v[size_t(bn[1])]) * 0.125f;
      } else {
        next[i] = v[i];  // a corner or a non-manifold vertex stays
      }
    }
    // Odd vertices.
    for (size_t e = 0; e < topo.edges.size(); ++e) {
      const EdgeInfo& ed = topo.edges[e];
      Vec3f a = v[size_t(ed.a)], b = v[size_t(ed.b)];
      if (ed.faces == 2)
        next[v.size() + e] =
            (a + b) * 0.375f + (v[size_t(ed.opposite[0])] + v[size_t(ed.opposite[1])]) * 0.125f;
      else
        next[v.size() + e] = (a + b) * 0.5f;
    }
    std::vector<Vec3i> nf;
    nf.reserve(f.size() * 4);
    const int32_t base = int32_t(v.size());
    for (size_t t = 0; t < f.size(); ++t) {
      int32_t v0 = f[t].x, v1 = f[t].y, v2 = f[t].z;
      int32_t e01 = base + topo.faceEdges[t * 3], e12 = base + topo.faceEdges[t * 3 + 1],
              e20 = base + topo.faceEdges[t * 3 + 2];
      nf.push_back({v0, e01, e20});
      nf.push_back({v1, e12, e01});
      nf.push_back({v2, e20, e12});
      nf.push_back({e01, e12, e20});
    }
    v = std::move(next);
    f = std::move(nf);
  }
  // Limit positions.
  if (levels > 0) {
    Topology topo = buildTopology(v.size(), f);
    std::vector<Vec3f> limit(v.size());
    for (size_t i = 0; i < v.size(); ++i) {
      const auto& nb = topo.neighbours[i];
      const auto& bn = topo.boundaryNeighbours[i];
      if (nb.empty()) {
        limit[i] = v[i];
      } else if (bn.empty()) {
        float beta = loopBeta(nb.size());
        float chi = 1.0f / (float(nb.size()) + 3.0f / (8.0f * beta));
        Vec3f sum(0);
        for (int32_t n : nb) sum += v[size_t(n)];
        limit[i] = v[i] * (1 - float(nb.size()) * chi) + sum * chi;
      } else if (bn.size() == 2) {
        limit[i] = v[i] * 0.6f + (v[size_t(bn[0])] + v[size_t(bn[1])]) * 0.2f;
      } else {
        limit[i] = v[i];
      }
    }
    v = std::move(limit);
  }
  Mesh m;
  m.positions = std::move(v);
  m.indices = std::move(f);
  computeVertexNormals(m);
  return m;
}

// ---------------------------------------------------------------------- curves

int curveSegmentCount(const CurveDescription& c) {
  if (c.degree != 2 && c.degree != 3)
    throw InputError(fmt::format("curve degree {} is not supported (2 or 3)", c.degree));
  const int n = int(c.points.size());
  int segments = 0;
  if (c.basis == CurveBasis::Bezier) {
    // Segments share their end points: 4, 7, 10, ... points for cubics.
    if (n < c.degree + 1 || (n - 1) % c.degree != 0)
      throw InputError(
          fmt::format("a degree-{} Bezier curve needs {} + {}k control points, found {}", c.degree,
                      c.degree + 1, c.degree, n));
    segments = (n - 1) / c.degree;
  } else {
    if (n < c.degree + 1)
      throw InputError(
          fmt::format("a degree-{} B-spline needs at least {} control points, found {}", c.degree,
                      c.degree + 1, n));
    segments = n - c.degree;
  }
  return segments;
}

void appendCurveSegments(const CurveDescription& c, std::vector<CurveSegment>& segments,
                         std::vector<CurveNormals>& normals) {
  const int count = curveSegmentCount(c);
  for (const Vec3f& p : c.points)
    if (!isFinite(p)) throw InputError("curve control point is not finite");
  if (!std::isfinite(c.width0) || !std::isfinite(c.width1) || c.width0 < 0 || c.width1 < 0)
    throw InputError("curve width must be finite and not negative");
  if (c.type == CurveType::Ribbon && c.normals.size() != size_t(count) + 1)
    throw InputError(fmt::format("a ribbon curve with {} segments needs {} normals, found {}",
                                 count, count + 1, c.normals.size()));
  if (c.splitDepth < 0 || c.splitDepth > 10)
    throw InputError(fmt::format("curve splitdepth {} is not in [0, 10]", c.splitDepth));
  for (int s = 0; s < count; ++s) {
    const Vec3f* p =
        c.basis == CurveBasis::Bezier ? &c.points[size_t(s * c.degree)] : &c.points[size_t(s)];
    std::array<Vec3f, 4> b;
    if (c.degree == 3) {
      if (c.basis == CurveBasis::Bezier) {
        for (int k = 0; k < 4; ++k) b[k] = p[k];
      } else {
        b[0] = (p[0] + p[1] * 4.0f + p[2]) * (1.0f / 6.0f);
        b[1] = (p[1] * 2.0f + p[2]) * (1.0f / 3.0f);
        b[2] = (p[1] + p[2] * 2.0f) * (1.0f / 3.0f);
        b[3] = (p[1] + p[2] * 4.0f + p[3]) * (1.0f / 6.0f);
      }
    } else {
      Vec3f q0, q1, q2;
      if (c.basis == CurveBasis::Bezier) {
        q0 = p[0], q1 = p[1], q2 = p[2];
      } else {
        q0 = (p[0] + p[1]) * 0.5f, q1 = p[1], q2 = (p[1] + p[2]) * 0.5f;
      }
      // Degree elevation to a cubic.
      b = {q0, q0 * (1.0f / 3.0f) + q1 * (2.0f / 3.0f), q1 * (2.0f / 3.0f) + q2 * (1.0f / 3.0f),
           q2};
    }
    // pbrt: each segment its own curve, with the widths where it lies.
    const float t0 = float(s) / float(count), t1 = float(s + 1) / float(count);
    const float w0 = c.width0 * (1 - t0) + c.width1 * t0;
    const float w1 = c.width0 * (1 - t1) + c.width1 * t1;
    if (c.type == CurveType::Ribbon) {
      const CurveNormals n{c.normals[size_t(s)], c.normals[size_t(s + 1)]};
      if (!(length(n[0]) > 0) || !(length(n[1]) > 0) || !isFinite(n[0]) || !isFinite(n[1]))
        throw InputError("a ribbon curve's normal is zero or not finite");
      appendCurveSegments(b, w0, w1, &n, c.splitDepth, segments, &normals);
    } else {
      appendCurveSegments(b, w0, w1, nullptr, c.splitDepth, segments, nullptr);
    }
  }
}

void computeVertexNormals(Mesh& m) {
  m.normals.assign(m.positions.size(), Vec3f(0));
  for (const Vec3i& t : m.indices) {
    Vec3f p0 = m.positions[size_t(t.x)], p1 = m.positions[size_t(t.y)],
          p2 = m.positions[size_t(t.z)];
    Vec3f n = cross(p1 - p0, p2 - p0);
    for (int k = 0; k < 3; ++k) m.normals[size_t(t[k])] += n;
  }
  for (Vec3f& n : m.normals) {
    float len = length(n);
    n = std::isfinite(len) && len > 0 ? n / len : Vec3f(0, 0, 1);
  }
}

float meshArea(const Mesh& m) {
  double a = 0;
  for (const Vec3i& t : m.indices) {
    Vec3f p0 = m.positions[size_t(t.x)], p1 = m.positions[size_t(t.y)],
          p2 = m.positions[size_t(t.z)];
    a += 0.5 * length(cross(p1 - p0, p2 - p0));
  }
  return float(a);
}

bool normalsPerpendicularToFaces(const Mesh& m) {
  if (m.normals.empty() || m.normals.size() != m.positions.size() || m.indices.empty())
    return false;
  for (const Vec3i& t : m.indices) {
    Vec3f p0 = m.positions[size_t(t.x)], p1 = m.positions[size_t(t.y)],
          p2 = m.positions[size_t(t.z)];
    Vec3f g = cross(p1 - p0, p2 - p0);
    float lg = length(g);
    if (!(lg > 0)) continue;
    for (int k = 0; k < 3; ++k) {
      Vec3f n = m.normals[size_t(t[k])];
      float ln = length(n);
      if (!(ln > 0)) continue;
      if (std::abs(dot(n, g)) > 0.01f * ln * lg) return false;
    }
  }
  return true;
}

}  // namespace ferry
