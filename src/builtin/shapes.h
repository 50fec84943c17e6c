// Mesh primitives for the procedural scenes, each paired with a function that
// gives its exact vertex and triangle count from its parameters alone. The
// built-ins describe themselves from those counts (without making geometry),
// so every primitive's topology must depend on its parameters only, never on
// random numbers or positions.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "core/math.h"
#include "scene/scene.h"

namespace ferry::builtin {

struct MeshCounts {
  uint64_t vertices = 0;
  uint64_t triangles = 0;

  MeshCounts& operator+=(const MeshCounts& o) {
    vertices += o.vertices;
    triangles += o.triangles;
    return *this;
  }
  friend MeshCounts operator+(MeshCounts a, const MeshCounts& b) { return a += b; }
  friend MeshCounts operator*(MeshCounts a, uint64_t n) {
    return {a.vertices * n, a.triangles * n};
  }
  friend bool operator==(const MeshCounts&, const MeshCounts&) = default;
};

// Appends vertices and triangles to a Mesh; reserves the exact size up front.
class MeshBuilder {
 public:
  MeshBuilder(bool withNormals, bool withUvs, MeshCounts expected);

  int32_t vertex(Vec3f p, Vec3f n = {0, 1, 0}, Vec2f uv = {0, 0});
  void triangle(int32_t a, int32_t b, int32_t c) { mesh_.indices.push_back({a, b, c}); }
  // a, b, c, d counter-clockwise seen from the side the normal points to.
  void quad(int32_t a, int32_t b, int32_t c, int32_t d) {
    triangle(a, b, c);
    triangle(a, c, d);
  }
  int32_t vertexCount() const { return static_cast<int32_t>(mesh_.positions.size()); }
  bool hasNormals() const { return withNormals_; }
  bool hasUvs() const { return withUvs_; }
  Mesh& mesh() { return mesh_; }
  Mesh finish() { return std::move(mesh_); }

 private:
  Mesh mesh_;
  bool withNormals_, withUvs_;
};

// A generalized cylinder through `centres` (one ring each) with a seam column
// duplicated for uvs; open at both ends. u goes around, v along the length
// (`vPerUnit` repeats per unit of length).
MeshCounts tubeCounts(int rings, int sides);
void addTube(MeshBuilder& b, std::span<const Vec3f> centres, std::span<const float> radii,
             int sides, float vPerUnit = 1.0f, float twist = 0.0f);

// A strip of quads along `centres`; each point has a unit side vector and a
// width. u runs across the strip from u0 to u1, v from 0 to 1 along it.
MeshCounts ribbonCounts(int segments);
void addRibbon(MeshBuilder& b, std::span<const Vec3f> centres, std::span<const Vec3f> sides,
               std::span<const float> widths, float u0 = 0, float u1 = 1);

// A subdivided cube projected by `surface` (called with unit directions);
// normals are taken from the surface by finite differences, so seams between
// cube faces do not show. uvs are per face.
MeshCounts cubeSphereCounts(int n);
void addCubeSphere(MeshBuilder& b, int n, const std::function<Vec3f(Vec3f)>& surface);

// Latitude-longitude sphere with single-triangle fans at the poles.
MeshCounts uvSphereCounts(int latitudes, int longitudes);
void addUvSphere(MeshBuilder& b, int latitudes, int longitudes, Vec3f centre, float radius);

// A regular (nu x nv) grid of quads; `at(u, v)` gives the position for u, v in [0, 1].
MeshCounts gridCounts(int nu, int nv);
void addGrid(MeshBuilder& b, int nu, int nv, const std::function<Vec3f(float, float)>& at,
             Vec2f uvScale = {1, 1});

// A disc-like cap: one apex vertex and `rings` rings of `segments` (+1 seam)
// vertices; `at(r, phi)` gives the position for r in [0, 1] (0: apex) and
// `uvOf(position)` its uv. Normals are left at +y for the caller to fill.
MeshCounts polarCapCounts(int rings, int segments);
void addPolarCap(MeshBuilder& b, int rings, int segments,
                 const std::function<Vec3f(float, float)>& at,
                 const std::function<Vec2f(Vec3f)>& uvOf);

// Area-weighted vertex normals from the triangles (for shapes without an
// analytic normal); vertices on uv seams get slightly different normals.
void computeVertexNormals(Mesh& mesh);

// Any unit vector perpendicular to `v`.
Vec3f perpendicular(Vec3f v);

}  // namespace ferry::builtin
