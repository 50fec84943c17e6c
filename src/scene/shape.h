// A kind of geometry other than a triangle mesh (spheres, curves, volume
// bricks): what the scene holds (Scene::geometries), the partitioners weigh
// and place, the proxies bound, a TraceBackend intersects, shading rebuilds
// and part files store. Triangle meshes stay Scene::meshes, the kind every
// stage is tuned for. Each kind registers a reader by its name
// (shapes/shape_kinds.cpp), so a part file stores a shape as its kind's name
// and its record. Adding a kind: docs/architecture.md.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "core/math.h"
#include "core/record.h"

namespace ferry {

// What crossing tests cost a trace: a volume's tracking steps (its real
// and null collisions, majorant cells); surfaces add nothing.
struct ShapeWork {
  uint64_t realCollisions = 0;
  uint64_t nullCollisions = 0;
  uint64_t cells = 0;
  void add(const ShapeWork& o) {
    realCollisions += o.realCollisions;
    nullCollisions += o.nullCollisions;
    cells += o.cells;
  }
};

// A point on a shape, in the shape's own (object) space.
struct ShapeSurface {
  Vec3f position;
  Vec3f geometricNormal;  // unit, outwards
  Vec3f shadingNormal;    // unit, on the geometric normal's side
  Vec2f uv;               // texture coordinates
  Vec3f tangent;          // dp/du where the kind has one (curves: along the fibre); else 0
  // How far rays leaving the point start from it along the normal, beyond
  // the usual few ulps: a fibre's crossing is approximate within its width.
  float originOffset = 0;
};

class Shape {
 public:
  virtual ~Shape() = default;
  // The name its kind is registered under (shapes/shape_kinds.cpp).
  virtual std::string_view kind() const = 0;
  virtual uint32_t primitiveCount() const = 0;
  virtual Box3f primitiveBounds(uint32_t primitive) const = 0;
  // The union of the primitives' bounds.
  Box3f bounds() const;
  // Bytes it holds in memory (its share of a rank's memory budget).
  virtual uint64_t bytes() const = 0;
  // The nearest crossing of `primitive` by origin + t direction with t in
  // (tnear, tfar): its t and the (u, v) surface() reads back. Deterministic:
  // the same ray gives the same answer on every rank and thread.
  virtual bool intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                         float& t, Vec2f& uv) const = 0;
  // The same, adding what the test cost to `work`.
  virtual bool intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                         float& t, Vec2f& uv, ShapeWork& /*work*/) const {
    return intersect(primitive, origin, direction, tnear, tfar, t, uv);
  }
  // Traversal bounds tighter than primitiveBounds: each primitive cut into
  // piecesPerPrimitive() pieces (a power of two), each with its own box.
  // intersectPiece finds the crossings inside its piece's box; the nearest
  // over a primitive's pieces is intersect's answer, bit for bit.
  virtual uint32_t piecesPerPrimitive() const { return 1; }
  virtual Box3f pieceBounds(uint32_t primitive, uint32_t /*piece*/) const {
    return primitiveBounds(primitive);
  }
  virtual bool intersectPiece(uint32_t primitive, uint32_t /*piece*/, Vec3f origin, Vec3f direction,
                              float tnear, float tfar, float& t, Vec2f& uv, ShapeWork& work) const {
    return intersect(primitive, origin, direction, tnear, tfar, t, uv, work);
  }
  // Flat cubic Bézier curves that Embree traces as its own geometry: four
  // control points (x, y, z, radius) a primitive, the index of each
  // primitive's first, and the straight pieces each is cut into. Empty for
  // other kinds. For them intersect() follows Embree's rule for its flat
  // curves, so both backends find the same crossings.
  struct FlatCurves {
    std::span<const Vec4f> points;
    std::span<const uint32_t> first;
    int tessellation = 0;
  };
  virtual FlatCurves flatCurves() const { return {}; }
  virtual ShapeSurface surface(uint32_t primitive, Vec2f uv) const = 0;
  // The same, seen along `direction` (object space, the ray that hit it):
  // for kinds whose surface faces the ray (flat curves).
  virtual ShapeSurface surface(uint32_t primitive, Vec2f uv, Vec3f /*direction*/) const {
    return surface(primitive, uv);
  }
  // A shape of the listed primitives only (in that order), each crossed
  // exactly as here; null when the kind cannot be cut (partitioning then
  // keeps it whole).
  virtual std::shared_ptr<const Shape> subset(std::span<const uint32_t> /*primitives*/) const {
    return nullptr;
  }
  // A volume (shapes/volume_brick.h) is crossed where a ray collides in its
  // medium; shading scatters there instead of reading a surface: the
  // scattering albedo at `point` (the shape's space) of the primitive that
  // found the collision, and the phase function's asymmetry g. Surfaces
  // answer false.
  virtual bool isVolume() const { return false; }
  virtual Vec3f volumeAlbedo(uint32_t /*primitive*/, Vec3f /*point*/) const { return Vec3f(0); }
  virtual float volumePhaseG() const { return 0; }
  virtual void write(RecordWriter& record) const = 0;
  // A line for people: the kind and its size.
  virtual std::string describe() const = 0;
};

}  // namespace ferry
