#include "builtin/shapes.h"

#include <cmath>

#include "core/error.h"

namespace ferry::builtin {

MeshBuilder::MeshBuilder(bool withNormals, bool withUvs, MeshCounts expected)
    : withNormals_(withNormals), withUvs_(withUvs) {
  mesh_.positions.reserve(expected.vertices);
  if (withNormals) mesh_.normals.reserve(expected.vertices);
  if (withUvs) mesh_.uvs.reserve(expected.vertices);
  mesh_.indices.reserve(expected.triangles);
}

int32_t MeshBuilder::vertex(Vec3f p, Vec3f n, Vec2f uv) {
  mesh_.positions.push_back(p);
  if (withNormals_) mesh_.normals.push_back(n);
  if (withUvs_) mesh_.uvs.push_back(uv);
  return static_cast<int32_t>(mesh_.positions.size() - 1);
}

Vec3f perpendicular(Vec3f v) {
  Vec3f axis = std::abs(v.x) > 0.9f ? Vec3f(0, 1, 0) : Vec3f(1, 0, 0);
  return normalize(cross(v, axis));
}

namespace {

Vec3f tangentAt(std::span<const Vec3f> c, size_t i) {
  size_t a = i == 0 ? 0 : i - 1;
  size_t b = i + 1 < c.size() ? i + 1 : i;
  Vec3f d = c[b] - c[a];
  float len = length(d);
  return len > 0 ? d / len : Vec3f(0, 1, 0);
}

}  // namespace

MeshCounts tubeCounts(int rings, int sides) {
  return {uint64_t(rings) * uint64_t(sides + 1), 2 * uint64_t(rings - 1) * uint64_t(sides)};
}

void addTube(MeshBuilder& b, std::span<const Vec3f> centres, std::span<const float> radii,
             int sides, float vPerUnit, float twist) {
  FERRY_CHECK_GE(centres.size(), 2);
  FERRY_CHECK_EQ(radii.size(), centres.size());
  FERRY_CHECK_GE(sides, 3);
  const int32_t first = b.vertexCount();
  const int stride = sides + 1;
  // Parallel transport keeps the rings from twisting where the path bends.
  Vec3f normal = perpendicular(tangentAt(centres, 0));
  float travelled = 0;
  for (size_t i = 0; i < centres.size(); ++i) {
    Vec3f t = tangentAt(centres, i);
    Vec3f projected = normal - t * dot(normal, t);
    normal = length(projected) > 1e-6f ? normalize(projected) : perpendicular(t);
    Vec3f binormal = cross(t, normal);
    if (i > 0) travelled += length(centres[i] - centres[i - 1]);
    for (int j = 0; j <= sides; ++j) {
      float a = 2 * kPi * float(j) / float(sides) + twist * float(i);
      Vec3f dir = normal * std::cos(a) + binormal * std::sin(a);
      b.vertex(centres[i] + dir * radii[i], dir, {float(j) / float(sides), travelled * vPerUnit});
    }
  }
  for (size_t i = 0; i + 1 < centres.size(); ++i)
    for (int j = 0; j < sides; ++j) {
      int32_t v00 = first + int32_t(i) * stride + j;
      int32_t v10 = v00 + stride;
      b.quad(v00, v00 + 1, v10 + 1, v10);
    }
}

MeshCounts ribbonCounts(int segments) {
  return {2 * uint64_t(segments + 1), 2 * uint64_t(segments)};
}

void addRibbon(MeshBuilder& b, std::span<const Vec3f> centres, std::span<const Vec3f> sides,
               std::span<const float> widths, float u0, float u1) {
  FERRY_CHECK_GE(centres.size(), 2);
  FERRY_CHECK_EQ(sides.size(), centres.size());
  FERRY_CHECK_EQ(widths.size(), centres.size());
  const int32_t first = b.vertexCount();
  const float segments = float(centres.size() - 1);
  for (size_t i = 0; i < centres.size(); ++i) {
    Vec3f t = tangentAt(centres, i);
    Vec3f n = cross(sides[i], t);
    float len = length(n);
    n = len > 0 ? n / len : Vec3f(0, 1, 0);
    float v = float(i) / segments;
    Vec3f half = sides[i] * (0.5f * widths[i]);
    b.vertex(centres[i] - half, n, {u0, v});
    b.vertex(centres[i] + half, n, {u1, v});
  }
  for (size_t i = 0; i + 1 < centres.size(); ++i) {
    int32_t l0 = first + int32_t(2 * i);
    b.quad(l0, l0 + 1, l0 + 3, l0 + 2);
  }
}

MeshCounts cubeSphereCounts(int n) {
  return {6 * uint64_t(n + 1) * uint64_t(n + 1), 12 * uint64_t(n) * uint64_t(n)};
}

void addCubeSphere(MeshBuilder& b, int n, const std::function<Vec3f(Vec3f)>& surface) {
  FERRY_CHECK_GE(n, 1);
  struct Face {
    Vec3f normal, u, v;  // u x v = normal: counter-clockwise from outside
  };
  static const Face kFaces[6] = {
      {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
      {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}, {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
      {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}};
  const float eps = 1e-3f;
  for (const Face& f : kFaces) {
    const int32_t first = b.vertexCount();
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        // Equi-angular warp: cells of similar size over the whole sphere.
        float a = std::tan((2 * float(i) / float(n) - 1) * kPi / 4);
        float c = std::tan((2 * float(j) / float(n) - 1) * kPi / 4);
        Vec3f dir = normalize(f.normal + f.u * a + f.v * c);
        Vec3f p = surface(dir);
        // A frame from the direction alone, so both copies of a seam vertex agree.
        Vec3f t1 = perpendicular(dir), t2 = cross(dir, t1);
        Vec3f du = surface(normalize(dir + t1 * eps)) - surface(normalize(dir - t1 * eps));
        Vec3f dv = surface(normalize(dir + t2 * eps)) - surface(normalize(dir - t2 * eps));
        Vec3f normal = cross(du, dv);
        float len = length(normal);
        normal = len > 0 ? normal / len : dir;
        if (dot(normal, dir) < 0) normal = -normal;
        b.vertex(p, normal, {float(i) / float(n), float(j) / float(n)});
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        int32_t v00 = first + j * (n + 1) + i;
        int32_t v01 = v00 + (n + 1);
        b.quad(v00, v00 + 1, v01 + 1, v01);
      }
  }
}

MeshCounts uvSphereCounts(int latitudes, int longitudes) {
  return {uint64_t(latitudes + 1) * uint64_t(longitudes + 1),
          2 * uint64_t(longitudes) * uint64_t(latitudes - 1)};
}

void addUvSphere(MeshBuilder& b, int latitudes, int longitudes, Vec3f centre, float radius) {
  FERRY_CHECK_GE(latitudes, 2);
  FERRY_CHECK_GE(longitudes, 3);
  const int32_t first = b.vertexCount();
  const int stride = longitudes + 1;
  for (int i = 0; i <= latitudes; ++i) {
    float theta = kPi * float(i) / float(latitudes);
    // Exact poles and equator keep the bounds exactly +-radius.
    float st = std::sin(theta), ct = std::cos(theta);
    if (i == 0) st = 0, ct = 1;
    if (i == latitudes) st = 0, ct = -1;
    if (latitudes % 2 == 0 && i == latitudes / 2) st = 1, ct = 0;
    for (int j = 0; j <= longitudes; ++j) {
      float phi = 2 * kPi * float(j) / float(longitudes);
      Vec3f dir{st * std::cos(phi), ct, st * std::sin(phi)};
      if (longitudes % 4 == 0) {  // exact +-x and +-z where the grid has them
        int q = j % longitudes;
        if (q == 0) dir = {st, ct, 0};
        if (q == longitudes / 4) dir = {0, ct, st};
        if (q == longitudes / 2) dir = {-st, ct, 0};
        if (q == 3 * longitudes / 4) dir = {0, ct, -st};
      }
      b.vertex(centre + dir * radius, dir,
               {float(j) / float(longitudes), 1 - float(i) / float(latitudes)});
    }
  }
  for (int i = 0; i < latitudes; ++i)
    for (int j = 0; j < longitudes; ++j) {
      int32_t a = first + i * stride + j, bb = a + 1, d = a + stride, c = d + 1;
      if (i != 0) b.triangle(a, bb, c);
      if (i != latitudes - 1) b.triangle(a, c, d);
    }
}

MeshCounts gridCounts(int nu, int nv) {
  return {uint64_t(nu + 1) * uint64_t(nv + 1), 2 * uint64_t(nu) * uint64_t(nv)};
}

void addGrid(MeshBuilder& b, int nu, int nv, const std::function<Vec3f(float, float)>& at,
             Vec2f uvScale) {
  FERRY_CHECK_GE(nu, 1);
  FERRY_CHECK_GE(nv, 1);
  const int32_t first = b.vertexCount();
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      float u = float(i) / float(nu), v = float(j) / float(nv);
      b.vertex(at(u, v), {0, 1, 0}, {u * uvScale.x, v * uvScale.y});
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      int32_t v00 = first + j * (nu + 1) + i;
      int32_t v01 = v00 + (nu + 1);
      b.quad(v00, v00 + 1, v01 + 1, v01);
    }
}

MeshCounts polarCapCounts(int rings, int segments) {
  return {1 + uint64_t(rings) * uint64_t(segments + 1),
          uint64_t(segments) + 2 * uint64_t(rings - 1) * uint64_t(segments)};
}

void addPolarCap(MeshBuilder& b, int rings, int segments,
                 const std::function<Vec3f(float, float)>& at,
                 const std::function<Vec2f(Vec3f)>& uvOf) {
  FERRY_CHECK_GE(rings, 1);
  FERRY_CHECK_GE(segments, 3);
  Vec3f apex = at(0, 0);
  const int32_t apexIndex = b.vertex(apex, {0, 1, 0}, uvOf(apex));
  const int stride = segments + 1;
  for (int i = 1; i <= rings; ++i)
    for (int j = 0; j <= segments; ++j) {
      // The seam column repeats the first one exactly, so the cap is closed.
      float phi = 2 * kPi * float(j % segments) / float(segments);
      Vec3f p = at(float(i) / float(rings), phi);
      b.vertex(p, {0, 1, 0}, uvOf(p));
    }
  auto ring = [&](int i, int j) { return apexIndex + 1 + (i - 1) * stride + j; };
  for (int j = 0; j < segments; ++j) b.triangle(apexIndex, ring(1, j + 1), ring(1, j));
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      int32_t a = ring(i, j), bb = ring(i + 1, j), c = ring(i + 1, j + 1), d = ring(i, j + 1);
      b.triangle(a, d, c);
      b.triangle(a, c, bb);
    }
}

void computeVertexNormals(Mesh& mesh) {
  std::vector<Vec3f> n(mesh.positions.size(), Vec3f(0));
  for (const Vec3i& t : mesh.indices) {
    Vec3f p0 = mesh.positions[t.x], p1 = mesh.positions[t.y], p2 = mesh.positions[t.z];
    Vec3f area = cross(p1 - p0, p2 - p0);  // length is twice the area: area weighting
    n[t.x] += area;
    n[t.y] += area;
    n[t.z] += area;
  }
  for (Vec3f& v : n) {
    float len = length(v);
    v = len > 0 ? v / len : Vec3f(0, 1, 0);
  }
  mesh.normals = std::move(n);
}

}  // namespace ferry::builtin
