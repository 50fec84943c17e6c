// An unstructured volume: tetrahedra over points that each carry a value in
// [0, 1], linear inside a cell, drawn through a transfer function (grey
// extinction scale x opacity(v), albedo colour(v)); VTK's .vtu cells arrive
// cut into tetrahedra.
//
// The cells are cut into clusters of kCellsPerCluster near cells (a Morton
// curve of their centroids); a cluster is a primitive with its box and one
// majorant. A cluster's crossing is a collision in the medium of its own
// cells, delta-tracked in its box with random numbers from the ray and the
// cluster's seed alone, so the nearest collision over the clusters a ray
// passes is the first in the whole field, on any rank and in any order, as
// for volume bricks. docs/volumes.md, "Unstructured volumes", says why.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "media/transfer_function.h"
#include "scene/shape.h"

namespace ferry {

constexpr uint32_t kCellsPerCluster = 32;

class UnstructuredVolume final : public Shape {
 public:
  using Tet = std::array<uint32_t, 4>;  // indices of its points
  // `values` one per point in [0, 1]; `tets` index `points`. Clusters the
  // cells (cluster k's tracking seeded by firstSeed + k: volumes that meet
  // take seeds of their own); throws InputError for an index out of range,
  // a value outside [0, 1] or not finite, a point not finite, no cells, or
  // no transfer function.
  static std::shared_ptr<UnstructuredVolume> make(std::vector<Vec3f> points,
                                                  std::vector<float> values, std::vector<Tet> tets,
                                                  std::shared_ptr<const TransferFunction> transfer,
                                                  uint32_t firstSeed = 0);

  std::string_view kind() const override { return "unstructured-volume"; }
  uint32_t primitiveCount() const override { return uint32_t(clusterSeed_.size()); }
  Box3f primitiveBounds(uint32_t cluster) const override { return clusterBox_[cluster]; }
  uint64_t bytes() const override;
  // What bytes() is for a volume of these counts (a plan's estimate).
  static uint64_t bytesFor(uint64_t points, uint64_t cells, uint64_t clusters);
  bool intersect(uint32_t cluster, Vec3f origin, Vec3f direction, float tnear, float tfar, float& t,
                 Vec2f& uv) const override;
  bool intersect(uint32_t cluster, Vec3f origin, Vec3f direction, float tnear, float tfar, float& t,
                 Vec2f& uv, ShapeWork& work) const override;
  ShapeSurface surface(uint32_t primitive, Vec2f uv) const override;
  std::shared_ptr<const Shape> subset(std::span<const uint32_t> clusters) const override;
  bool isVolume() const override { return true; }
  Vec3f volumeAlbedo(uint32_t cluster, Vec3f point) const override;
  void write(RecordWriter& record) const override;
  std::string describe() const override;
  static std::shared_ptr<const Shape> read(RecordReader& record);

  // The value at `point` in `cluster`'s cells (false: none of them holds it).
  bool valueAt(uint32_t cluster, Vec3f point, float& value) const;
  // The extinction at a value.
  float extinction(float value) const { return transfer_->scale() * transfer_->opacity(value); }
  uint32_t cellCount() const { return uint32_t(tets_.size()); }
  uint32_t pointCount() const { return uint32_t(points_.size()); }
  float majorant(uint32_t cluster) const { return clusterMajorant_[cluster]; }
  const std::shared_ptr<const TransferFunction>& transfer() const { return transfer_; }
  // Draws the volume through `transfer` instead: the majorants rebuilt from
  // the value range kept per cluster. Not while a ray crosses it.
  void restyle(std::shared_ptr<const TransferFunction> transfer);

 private:
  UnstructuredVolume() = default;
  // Boxes, value ranges and majorants of the clusters (clusterFirst_ and the cells set).
  void finish();
  void setMajorants();  // from the value ranges and the transfer function
  std::vector<Vec3f> points_;
  std::vector<float> values_;
  std::vector<Tet> tets_;               // cluster by cluster
  std::vector<uint32_t> clusterFirst_;  // cluster c: tets_[first[c], first[c + 1])
  std::vector<uint32_t> clusterSeed_;   // its place in the whole volume's order
  std::vector<Box3f> clusterBox_;
  std::vector<std::pair<float, float>> clusterRange_;  // its vertices' values, [low, high]
  std::vector<float> clusterMajorant_;
  std::shared_ptr<const TransferFunction> transfer_;
};

}  // namespace ferry
