// Analytic spheres (OSPRay's and ANARI's "sphere" geometry: particles,
// atoms): a centre and a radius each, intersected exactly, with pbrt's
// sphere parametrization, u = phi / 2 pi around +z from +x and
// v = theta / pi from +z.
#pragma once

#include <memory>
#include <vector>

#include "scene/shape.h"

namespace ferry {

class Spheres final : public Shape {
 public:
  // Throws InputError when the arrays differ in size or a centre or radius
  // is not finite or a radius not positive.
  Spheres(std::vector<Vec3f> centers, std::vector<float> radii);

  std::string_view kind() const override { return "spheres"; }
  uint32_t primitiveCount() const override { return uint32_t(centers_.size()); }
  Box3f primitiveBounds(uint32_t primitive) const override;
  uint64_t bytes() const override;
  using Shape::intersect;
  bool intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                 float& t, Vec2f& uv) const override;
  ShapeSurface surface(uint32_t primitive, Vec2f uv) const override;
  std::shared_ptr<const Shape> subset(std::span<const uint32_t> primitives) const override;
  void write(RecordWriter& record) const override;
  std::string describe() const override;
  static std::shared_ptr<const Shape> read(RecordReader& record);

  const std::vector<Vec3f>& centers() const { return centers_; }
  const std::vector<float>& radii() const { return radii_; }

 private:
  std::vector<Vec3f> centers_;
  std::vector<float> radii_;
};

}  // namespace ferry
