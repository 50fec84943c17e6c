// Curves (pbrt's "curve" shape; fur, hair, grass): cubic Bézier segments
// with a width at each end. A `flat` segment is a ribbon that always faces
// the ray; a `cylinder` segment is the same ribbon shaded as a tube (its
// normal turned about the tangent across the width); a `ribbon` segment is
// oriented by a normal at each end. Flat and cylinder segments are Embree's
// flat Bézier curves, crossed by Embree's rule (each cut into kTessellation
// straight pieces facing the ray) in both backends; ribbons are crossed by
// pbrt's recursive test. A hit's (u, v): u along the segment, v across the
// width from -1 to 1 (Embree's); surface() gives pbrt's (u along the whole
// curve, v from 0 to 1) and the tangent dp/du for hair shading.
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "scene/shape.h"

namespace ferry {

enum class CurveType : uint8_t { Flat = 0, Cylinder = 1, Ribbon = 2 };
// "flat", "cylinder", "ribbon"; false: none of them.
bool parseCurveType(std::string_view name, CurveType& type);
std::string_view curveTypeName(CurveType type);

struct CurveSegment {
  std::array<Vec3f, 4> points;   // Bézier control points
  float width0 = 0, width1 = 0;  // at the segment's ends
  float u0 = 0, u1 = 1;          // where it lies on its curve
};
// A ribbon segment's unit normals at its two ends.
using CurveNormals = std::array<Vec3f, 2>;

// The 2^splitDepth segments pbrt makes of one cubic Bézier curve (its
// `splitdepth`), each with the curve's widths (and a ribbon's normals,
// interpolated as pbrt does) where it lies. `normals` is null unless the
// curve is a ribbon; then `normalsOut` receives one pair per segment.
void appendCurveSegments(const std::array<Vec3f, 4>& points, float width0, float width1,
                         const CurveNormals* normals, int splitDepth,
                         std::vector<CurveSegment>& out, std::vector<CurveNormals>* normalsOut);

class Curves final : public Shape {
 public:
  // Throws InputError when a point, width or normal is not finite, a width
  // is negative or both ends' widths are 0, or a ribbon's normal is zero.
  // Ribbons need one normal pair per segment; the other types none.
  Curves(CurveType type, std::vector<CurveSegment> segments,
         std::vector<CurveNormals> normals = {});

  std::string_view kind() const override { return "curves"; }
  uint32_t primitiveCount() const override { return uint32_t(segments_.size()); }
  Box3f primitiveBounds(uint32_t primitive) const override;
  uint64_t bytes() const override;
  using Shape::intersect;
  bool intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                 float& t, Vec2f& uv) const override;
  ShapeSurface surface(uint32_t primitive, Vec2f uv) const override;
  ShapeSurface surface(uint32_t primitive, Vec2f uv, Vec3f direction) const override;
  FlatCurves flatCurves() const override;
  // The straight pieces Embree cuts a flat or cylinder segment into (its
  // tessellation rate).
  static constexpr int kTessellation = 4;
  // A ribbon segment is bounded for traversal in kTraversalPieces pieces
  // along its length (fewer when there are too many segments to number
  // them); Embree bounds the others itself.
  static constexpr uint32_t kTraversalPieces = 3;
  static uint32_t traversalPiecesFor(CurveType type, uint64_t segments);
  // Bytes a segment of the type holds (bytes() over the segment count).
  static uint64_t bytesPerSegment(CurveType type);
  uint32_t piecesPerPrimitive() const override { return pieces_; }
  Box3f pieceBounds(uint32_t primitive, uint32_t piece) const override;
  bool intersectPiece(uint32_t primitive, uint32_t piece, Vec3f origin, Vec3f direction,
                      float tnear, float tfar, float& t, Vec2f& uv, ShapeWork& work) const override;
  std::shared_ptr<const Shape> subset(std::span<const uint32_t> primitives) const override;
  void write(RecordWriter& record) const override;
  std::string describe() const override;
  static std::shared_ptr<const Shape> read(RecordReader& record);

  CurveType type() const { return type_; }
  const std::vector<CurveSegment>& segments() const { return segments_; }
  const std::vector<CurveNormals>& normals() const { return normals_; }

 private:
  // The nearest crossing in piece `piece` of `pieces` (1: the whole).
  bool crossPiece(uint32_t primitive, uint32_t piece, uint32_t pieces, Vec3f origin,
                  Vec3f direction, float tnear, float tfar, float& t, Vec2f& uv) const;

  // Embree's rule for a flat segment (its control points in points_).
  bool crossFlat(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                 float& t, Vec2f& uv) const;

  CurveType type_;
  uint32_t pieces_ = 1;
  std::vector<CurveSegment> segments_;
  std::vector<CurveNormals> normals_;
  // Flat and cylinder segments as Embree takes them: 4 control points each
  // (x, y, z, radius), and the index of each segment's first.
  std::vector<Vec4f> points_;
  std::vector<uint32_t> first_;
};

}  // namespace ferry
