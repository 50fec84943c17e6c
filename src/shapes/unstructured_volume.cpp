#include "shapes/unstructured_volume.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "core/error.h"
#include "media/tracking.h"

namespace ferry {
namespace {

float det3(Vec3f a, Vec3f b, Vec3f c) {
  return dot(a, cross(b, c));
}

// Spreads the low 10 bits of x to every third bit (a Morton code's axis).
uint32_t spread10(uint32_t x) {
  x &= 0x3ff;
  x = (x | (x << 16)) & 0x030000ff;
  x = (x | (x << 8)) & 0x0300f00f;
  x = (x | (x << 4)) & 0x030c30c3;
  x = (x | (x << 2)) & 0x09249249;
  return x;
}

}  // namespace

std::shared_ptr<UnstructuredVolume> UnstructuredVolume::make(
    std::vector<Vec3f> points, std::vector<float> values, std::vector<Tet> tets,
    std::shared_ptr<const TransferFunction> transfer, uint32_t firstSeed) {
  if (!transfer) throw InputError("an unstructured volume without a transfer function");
  if (tets.empty()) throw InputError("an unstructured volume without cells");
  if (values.size() != points.size())
    throw InputError(fmt::format("an unstructured volume of {} points has {} values", points.size(),
                                 values.size()));
  for (size_t i = 0; i < points.size(); ++i) {
    if (!isFinite(points[i]))
      throw InputError(fmt::format("an unstructured volume's point {} is not finite", i));
    if (!(values[i] >= 0 && values[i] <= 1))
      throw InputError(
          fmt::format("an unstructured volume's value {} is {} (not in [0, 1])", i, values[i]));
  }
  Box3f bounds;
  for (size_t c = 0; c < tets.size(); ++c)
    for (uint32_t p : tets[c]) {
      if (p >= points.size())
        throw InputError(fmt::format("an unstructured volume's cell {} names point {} of {}", c, p,
                                     points.size()));
      bounds.extend(points[p]);
    }
  // Clusters: the cells along a Morton curve of their centroids, in runs.
  std::vector<uint32_t> code(tets.size());
  const Vec3f size = max(bounds.size(), Vec3f(1e-30f));
  for (size_t c = 0; c < tets.size(); ++c) {
    const Tet& t = tets[c];
    const Vec3f centre =
        (points[t[0]] + points[t[1]] + points[t[2]] + points[t[3]]) * 0.25f - bounds.lower;
    uint32_t m = 0;
    for (int a = 0; a < 3; ++a)
      m |= spread10(uint32_t(std::clamp(centre[a] / size[a], 0.0f, 1.0f) * 1023.0f)) << a;
    code[c] = m;
  }
  std::vector<uint32_t> order(tets.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return code[a] < code[b]; });
  std::shared_ptr<UnstructuredVolume> v(new UnstructuredVolume());
  v->tets_.reserve(tets.size());
  for (uint32_t c : order) v->tets_.push_back(tets[c]);
  for (uint32_t first = 0; first < tets.size(); first += kCellsPerCluster) {
    v->clusterFirst_.push_back(first);
    v->clusterSeed_.push_back(firstSeed + uint32_t(v->clusterSeed_.size()));
  }
  v->clusterFirst_.push_back(uint32_t(tets.size()));
  v->points_ = std::move(points);
  v->values_ = std::move(values);
  v->transfer_ = std::move(transfer);
  v->finish();
  return v;
}

void UnstructuredVolume::finish() {
  const size_t clusters = clusterSeed_.size();
  clusterBox_.assign(clusters, Box3f{});
  clusterRange_.assign(clusters, {1.0f, 0.0f});
  for (size_t c = 0; c < clusters; ++c)
    for (uint32_t i = clusterFirst_[c]; i < clusterFirst_[c + 1]; ++i)
      for (uint32_t p : tets_[i]) {
        clusterBox_[c].extend(points_[p]);
        clusterRange_[c].first = std::min(clusterRange_[c].first, values_[p]);
        clusterRange_[c].second = std::max(clusterRange_[c].second, values_[p]);
      }
  setMajorants();
}

void UnstructuredVolume::setMajorants() {
  // Linear inside a cell: its values lie between its vertices'.
  clusterMajorant_.resize(clusterRange_.size());
  for (size_t c = 0; c < clusterRange_.size(); ++c)
    clusterMajorant_[c] =
        transfer_->scale() *
        transfer_->opacityRange(clusterRange_[c].first, clusterRange_[c].second).second;
}

void UnstructuredVolume::restyle(std::shared_ptr<const TransferFunction> transfer) {
  if (!transfer) throw InputError("an unstructured volume restyled without a transfer function");
  transfer_ = std::move(transfer);
  setMajorants();
}

uint64_t UnstructuredVolume::bytesFor(uint64_t points, uint64_t cells, uint64_t clusters) {
  // Per cluster: first cell, seed, value range, box, majorant.
  return sizeof(UnstructuredVolume) + points * (sizeof(Vec3f) + sizeof(float)) +
         cells * sizeof(Tet) + clusters * (4 * sizeof(uint32_t) + sizeof(Box3f) + sizeof(float));
}

uint64_t UnstructuredVolume::bytes() const {
  return bytesFor(points_.size(), tets_.size(), clusterSeed_.size());
}

bool UnstructuredVolume::valueAt(uint32_t cluster, Vec3f p, float& value) const {
  for (uint32_t i = clusterFirst_[cluster]; i < clusterFirst_[cluster + 1]; ++i) {
    const Tet& t = tets_[i];
    const Vec3f a = points_[t[0]], b = points_[t[1]] - a, c = points_[t[2]] - a,
                d = points_[t[3]] - a, q = p - a;
    const float volume = det3(b, c, d);
    if (volume == 0) continue;  // a flat cell holds no point
    const float inv = 1 / volume;
    const float l1 = det3(q, c, d) * inv, l2 = det3(b, q, d) * inv, l3 = det3(b, c, q) * inv;
    const float l0 = 1 - l1 - l2 - l3;
    if (l0 < 0 || l1 < 0 || l2 < 0 || l3 < 0) continue;
    value = std::clamp(
        l0 * values_[t[0]] + l1 * values_[t[1]] + l2 * values_[t[2]] + l3 * values_[t[3]], 0.0f,
        1.0f);
    return true;
  }
  return false;
}

bool UnstructuredVolume::intersect(uint32_t cluster, Vec3f origin, Vec3f direction, float tnear,
                                   float tfar, float& t, Vec2f& uv) const {
  ShapeWork ignored;
  return intersect(cluster, origin, direction, tnear, tfar, t, uv, ignored);
}

bool UnstructuredVolume::intersect(uint32_t cluster, Vec3f origin, Vec3f direction, float tnear,
                                   float tfar, float& t, Vec2f& uv, ShapeWork& work) const {
  const float majorant = clusterMajorant_[cluster];
  if (!(majorant > 0)) return false;
  // From t = 0 whatever tnear is, and only up to tfar: the decisions before
  // tfar are the same for any tfar, so every rank finds the same collision.
  float s = 0, end = tfar;
  const Vec3f inverse(1 / direction.x, 1 / direction.y, 1 / direction.z);
  if (!clusterBox_[cluster].clipRay(origin, inverse, s, end)) return false;
  ++work.cells;
  TrackingRandom random(rayTrackingKey(origin, direction, clusterSeed_[cluster]), 0);
  for (;;) {
    s += exponentialDistance(random.next(), majorant);
    if (!(s < end)) return false;
    float value = 0;
    const float sigma = valueAt(cluster, origin + direction * s, value) ? extinction(value) : 0.0f;
    if (random.next() * majorant < sigma && s > tnear) {
      ++work.realCollisions;
      t = s;
      uv = {value, 0};
      return true;
    }
    ++work.nullCollisions;
  }
}

ShapeSurface UnstructuredVolume::surface(uint32_t, Vec2f uv) const {
  // (Shading scatters at a volume's collisions; it reads no surface.)
  return {Vec3f(0), {0, 0, 1}, {0, 0, 1}, uv};
}

Vec3f UnstructuredVolume::volumeAlbedo(uint32_t cluster, Vec3f point) const {
  float value = 0;
  // (A collision lies in one of the cluster's cells; within rounding, the nearest value.)
  if (!valueAt(cluster, point, value)) {
    float best = kInfinity;
    for (uint32_t i = clusterFirst_[cluster]; i < clusterFirst_[cluster + 1]; ++i)
      for (uint32_t p : tets_[i])
        if (const float d = dot(points_[p] - point, points_[p] - point); d < best) {
          best = d;
          value = values_[p];
        }
  }
  return transfer_->color(value);
}

std::shared_ptr<const Shape> UnstructuredVolume::subset(std::span<const uint32_t> clusters) const {
  std::shared_ptr<UnstructuredVolume> v(new UnstructuredVolume());
  std::vector<uint32_t> renumbered(points_.size(), UINT32_MAX);
  for (uint32_t c : clusters) {
    v->clusterFirst_.push_back(uint32_t(v->tets_.size()));
    v->clusterSeed_.push_back(clusterSeed_[c]);
    for (uint32_t i = clusterFirst_[c]; i < clusterFirst_[c + 1]; ++i) {
      Tet t = tets_[i];
      for (uint32_t& p : t) {
        if (renumbered[p] == UINT32_MAX) {
          renumbered[p] = uint32_t(v->points_.size());
          v->points_.push_back(points_[p]);
          v->values_.push_back(values_[p]);
        }
        p = renumbered[p];
      }
      v->tets_.push_back(t);
    }
  }
  v->clusterFirst_.push_back(uint32_t(v->tets_.size()));
  v->transfer_ = transfer_;
  v->finish();
  return v;
}

void UnstructuredVolume::write(RecordWriter& record) const {
  record.array<Vec3f>(points_);
  record.array<float>(values_);
  record.array<Tet>(tets_);
  record.array<uint32_t>(clusterFirst_);
  record.array<uint32_t>(clusterSeed_);
  record.array<TransferFunction::ColorPoint>(transfer_->colors());
  record.array<TransferFunction::OpacityPoint>(transfer_->opacities());
  record.pod(transfer_->scale());
}

std::shared_ptr<const Shape> UnstructuredVolume::read(RecordReader& record) {
  std::shared_ptr<UnstructuredVolume> v(new UnstructuredVolume());
  v->points_ = record.array<Vec3f>();
  v->values_ = record.array<float>();
  v->tets_ = record.array<Tet>();
  v->clusterFirst_ = record.array<uint32_t>();
  v->clusterSeed_ = record.array<uint32_t>();
  auto colors = record.array<TransferFunction::ColorPoint>();
  auto opacities = record.array<TransferFunction::OpacityPoint>();
  const float scale = record.pod<float>();
  try {
    v->transfer_ =
        std::make_shared<TransferFunction>(std::move(colors), std::move(opacities), scale);
  } catch (const std::invalid_argument& e) {
    record.fail(e.what());
  }
  if (v->values_.size() != v->points_.size())
    record.fail("an unstructured volume's values do not match its points");
  for (size_t i = 0; i < v->points_.size(); ++i)
    if (!isFinite(v->points_[i]) || !(v->values_[i] >= 0 && v->values_[i] <= 1))
      record.fail("an unstructured volume's point or value is out of range");
  for (const Tet& t : v->tets_)
    for (uint32_t p : t)
      if (p >= v->points_.size()) record.fail("an unstructured volume's cell names no point");
  const std::vector<uint32_t>& first = v->clusterFirst_;
  if (v->clusterSeed_.empty() || first.size() != v->clusterSeed_.size() + 1 || first.front() != 0 ||
      first.back() != v->tets_.size() || !std::is_sorted(first.begin(), first.end()))
    record.fail("an unstructured volume's clusters do not cover its cells");
  for (size_t c = 0; c + 1 < first.size(); ++c)
    if (first[c] == first[c + 1]) record.fail("an unstructured volume has an empty cluster");
  v->finish();
  return v;
}

std::string UnstructuredVolume::describe() const {
  return fmt::format("unstructured volume of {} tetrahedra over {} points, {} clusters",
                     tets_.size(), points_.size(), clusterSeed_.size());
}

}  // namespace ferry
