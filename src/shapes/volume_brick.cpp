#include "shapes/volume_brick.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/error.h"
#include "core/random.h"
#include "media/tracking.h"
#include "scene/scene.h"

namespace ferry {
namespace {

float greyExtinction(const VolumeBrick::Volume& v) {
  return v.sigmaA.x + v.sigmaS.x;
}

}  // namespace

VolumeBrick::VolumeBrick(std::shared_ptr<const Volume> volume, std::array<int, 3> lo,
                         std::array<int, 3> hi, SharedArray<float> samples)
    : volume_(std::move(volume)), lo_(lo), hi_(hi), samples_(std::move(samples)) {
  const Volume& v = *volume_;
  const SharedArray<float>& held = samples_;  // read only: a mapping stays shared
  size_t expected = 1;
  uint32_t seed = 0x7b5e11u;
  for (int a = 0; a < 3; ++a) {
    const int n = v.dims[a];
    if (n < 1 || lo[a] < 0 || hi[a] > n || lo[a] >= hi[a])
      throw InputError(fmt::format("a volume brick's cells {}..{} do not fit a grid of {} along {}",
                                   lo[a], hi[a], n, "xyz"[a]));
    first_[a] = std::max(lo[a] - 1, 0);
    count_[a] = std::min(hi[a], n - 1) - first_[a] + 1;
    expected *= size_t(count_[a]);
    unitLo_[a] = float(lo[a]) / float(n);
    unitSize_[a] = float(hi[a] - lo[a]) / float(n);
    seed = hashCombine(hashCombine(seed, uint32_t(n)), uint32_t(lo[a]));
  }
  seed_ = seed;
  if (samples_.size() != expected)
    throw InputError(fmt::format("a volume brick holds {} samples where its cells need {}",
                                 samples_.size(), expected));
  for (size_t i = 0; i < held.size(); ++i)
    if (!((held[i] >= 0 || v.normalise) && std::isfinite(held[i])))
      throw InputError(fmt::format("a volume brick's sample {} is {}", i, held[i]));
  if (!v.transfer && !(v.sigmaA.x + v.sigmaS.x == v.sigmaA.y + v.sigmaS.y &&
                       v.sigmaA.y + v.sigmaS.y == v.sigmaA.z + v.sigmaS.z))
    throw InputError("a volume brick's extinction is not grey");
  // Majorant cells: the largest extinction over the samples a cell's lookups read.
  int cells[3];
  for (int a = 0; a < 3; ++a)
    cells[a] = (hi[a] - lo[a] + kBrickMajorantVoxels - 1) / kBrickMajorantVoxels;
  const size_t cellCount = size_t(cells[0]) * size_t(cells[1]) * size_t(cells[2]);
  std::vector<float> majorants(cellCount);
  ranges_.resize(majorants.size());
  size_t i = 0;
  for (int cz = 0; cz < cells[2]; ++cz)
    for (int cy = 0; cy < cells[1]; ++cy)
      for (int cx = 0; cx < cells[0]; ++cx, ++i) {
        const int c[3] = {cx, cy, cz};
        int from[3], to[3];
        for (int a = 0; a < 3; ++a) {
          from[a] = lo[a] + c[a] * kBrickMajorantVoxels - 1;
          to[a] = std::min(lo[a] + (c[a] + 1) * kBrickMajorantVoxels, hi[a]);
        }
        // The samples held, row by row (as held: normalised after); those
        // outside the grid are 0.
        float low = kInfinity, high = -kInfinity;
        bool outside = false;
        for (int a = 0; a < 3; ++a) {
          if (from[a] < first_[a] || to[a] >= first_[a] + count_[a]) outside = true;
          from[a] = std::max(from[a], first_[a]);
          to[a] = std::min(to[a], first_[a] + count_[a] - 1);
        }
        for (int z = from[2]; z <= to[2]; ++z)
          for (int y = from[1]; y <= to[1]; ++y) {
            const float* row = held.data() +
                               (size_t(z - first_[2]) * size_t(count_[1]) + size_t(y - first_[1])) *
                                   size_t(count_[0]) +
                               size_t(from[0] - first_[0]);
            for (int x = 0; x <= to[0] - from[0]; ++x) {
              low = std::min(low, row[x]);
              high = std::max(high, row[x]);
            }
          }
        if (v.normalise) {  // (monotonic: the ends map to the ends)
          low = v.normalised(low);
          high = v.normalised(high);
        }
        if (outside) {
          low = std::min(low, 0.0f);
          high = std::max(high, 0.0f);
        }
        ranges_[i] = {low, high};
        majorants[i] = cellMajorant(v, low, high);
        largest_ = std::max(largest_, majorants[i]);
      }
  majorants_ = std::make_unique<MajorantGrid>(cells[0], cells[1], cells[2], std::move(majorants));
}

float VolumeBrick::cellMajorant(const Volume& v, float low, float high) {
  return v.transfer ? v.transfer->scale() * v.transfer->opacityRange(low, high).second
                    : greyExtinction(v) * high;
}

void VolumeBrick::restyle(std::shared_ptr<const Volume> volume) {
  const Volume& v = *volume;
  if (v.dims != volume_->dims || v.normalise != volume_->normalise ||
      v.valueLo != volume_->valueLo || v.valueRange != volume_->valueRange || !v.transfer)
    throw InputError("a volume brick restyled by another volume's grid");
  std::vector<float> majorants(ranges_.size());
  float largest = 0;
  for (size_t i = 0; i < ranges_.size(); ++i) {
    majorants[i] = cellMajorant(v, ranges_[i].first, ranges_[i].second);
    largest = std::max(largest, majorants[i]);
  }
  majorants_ = std::make_unique<MajorantGrid>(majorants_->cells(0), majorants_->cells(1),
                                              majorants_->cells(2), std::move(majorants));
  largest_ = largest;
  volume_ = std::move(volume);
}

std::shared_ptr<VolumeBrick> VolumeBrick::cut(std::shared_ptr<const Volume> volume,
                                              const DensityGrid& grid, std::array<int, 3> lo,
                                              std::array<int, 3> hi) {
  const int n[3] = {grid.nx(), grid.ny(), grid.nz()};
  int first[3], last[3];
  for (int a = 0; a < 3; ++a) {
    first[a] = std::clamp(lo[a] - 1, 0, n[a] - 1);
    last[a] = std::clamp(hi[a], 0, n[a] - 1);
  }
  std::vector<float> samples;
  samples.reserve(size_t(last[0] - first[0] + 1) * size_t(last[1] - first[1] + 1) *
                  size_t(last[2] - first[2] + 1));
  const std::vector<float>& values = grid.values();
  for (int z = first[2]; z <= last[2]; ++z)
    for (int y = first[1]; y <= last[1]; ++y) {
      const size_t row = (size_t(z) * size_t(n[1]) + size_t(y)) * size_t(n[0]);
      samples.insert(samples.end(), values.begin() + ptrdiff_t(row + size_t(first[0])),
                     values.begin() + ptrdiff_t(row + size_t(last[0]) + 1));
    }
  return std::make_shared<VolumeBrick>(std::move(volume), lo, hi, std::move(samples));
}

float VolumeBrick::sample(int x, int y, int z) const {
  const int p[3] = {x, y, z};
  for (int a = 0; a < 3; ++a)
    if (p[a] < first_[a] || p[a] >= first_[a] + count_[a]) return 0;
  const float held = samples_[(size_t(z - first_[2]) * size_t(count_[1]) + size_t(y - first_[1])) *
                                  size_t(count_[0]) +
                              size_t(x - first_[0])];
  return volume_->normalise ? volume_->normalised(held) : held;
}

float VolumeBrick::lookup(Vec3f p) const {
  const std::array<int, 3>& n = volume_->dims;
  const float sx = p.x * float(n[0]) - 0.5f, sy = p.y * float(n[1]) - 0.5f,
              sz = p.z * float(n[2]) - 0.5f;
  const float fx = std::floor(sx), fy = std::floor(sy), fz = std::floor(sz);
  if (!(fx >= -1 && fy >= -1 && fz >= -1 && fx < float(n[0]) && fy < float(n[1]) &&
        fz < float(n[2])))
    return 0;
  const int x = int(fx), y = int(fy), z = int(fz);
  const float dx = sx - fx, dy = sy - fy, dz = sz - fz;
  auto lerp = [](float t, float a, float b) { return (1 - t) * a + t * b; };
  const float d00 = lerp(dx, sample(x, y, z), sample(x + 1, y, z));
  const float d10 = lerp(dx, sample(x, y + 1, z), sample(x + 1, y + 1, z));
  const float d01 = lerp(dx, sample(x, y, z + 1), sample(x + 1, y, z + 1));
  const float d11 = lerp(dx, sample(x, y + 1, z + 1), sample(x + 1, y + 1, z + 1));
  return lerp(dz, lerp(dy, d00, d10), lerp(dy, d01, d11));
}

float VolumeBrick::extinction(float value) const {
  const Volume& v = *volume_;
  return v.transfer ? v.transfer->scale() * v.transfer->opacity(value) : greyExtinction(v) * value;
}

Box3f VolumeBrick::primitiveBounds(uint32_t) const {
  return volume_->gridFromWorld.inverse().transformBox({unitLo_, unitLo_ + unitSize_});
}

uint64_t VolumeBrick::bytes() const {
  int cells = 1;
  for (int a = 0; a < 3; ++a)
    cells *= (hi_[a] - lo_[a] + kBrickMajorantVoxels - 1) / kBrickMajorantVoxels;
  // Per majorant cell: the majorant and control (MajorantGrid), the value range.
  return sizeof(*this) + samples_.size() * sizeof(float) + size_t(cells) * sizeof(float) * 6;
}

bool VolumeBrick::intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear,
                            float tfar, float& t, Vec2f& uv) const {
  ShapeWork ignored;
  return intersect(primitive, origin, direction, tnear, tfar, t, uv, ignored);
}

bool VolumeBrick::intersect(uint32_t, Vec3f origin, Vec3f direction, float tnear, float tfar,
                            float& t, Vec2f& uv, ShapeWork& work) const {
  if (!(largest_ > 0)) return false;
  const Affine3f& toGrid = volume_->gridFromWorld;
  const Vec3f og = toGrid.transformPoint(origin), dg = toGrid.transformVector(direction);
  // The brick's cells as the unit cube the majorant cells cover (the same t).
  Vec3f ol, dl;
  for (int a = 0; a < 3; ++a) {
    ol[a] = (og[a] - unitLo_[a]) / unitSize_[a];
    dl[a] = dg[a] / unitSize_[a];
  }
  // From t = 0 whatever tnear is, and only up to tfar: the decisions before
  // tfar are the same for any tfar, so every rank finds the same collision.
  float t0 = 0, t1 = tfar;
  if (!clipToUnitCube(ol, dl, t0, t1)) return false;
  TrackingRandom random(rayTrackingKey(origin, direction, seed_), 0);
  bool found = false;
  majorants_->walk(ol, dl, t0, t1, [&](float a, float b, float majorant, const Vec3f&) {
    ++work.cells;
    if (!(majorant > 0)) return true;
    for (float s = a;;) {
      s += exponentialDistance(random.next(), majorant);
      if (!(s < b)) return true;
      const float sigma = extinction(lookup(og + dg * s));
      if (random.next() * majorant < sigma && s > tnear) {
        ++work.realCollisions;
        t = s;
        found = true;
        return false;
      }
      ++work.nullCollisions;
    }
  });
  uv = {0, 0};
  return found;
}

ShapeSurface VolumeBrick::surface(uint32_t, Vec2f uv) const {
  // (Shading scatters at a volume's collisions; it reads no surface.)
  return {Vec3f(0), {0, 0, 1}, {0, 0, 1}, uv};
}

Vec3f VolumeBrick::volumeAlbedo(uint32_t, Vec3f point) const {
  const Volume& v = *volume_;
  const float value = lookup(v.gridFromWorld.transformPoint(point));
  if (v.transfer) return v.transfer->color(value);
  const float sigmaT = greyExtinction(v);
  return sigmaT > 0 ? v.sigmaS * (1 / sigmaT) : Vec3f(0);
}

void VolumeBrick::write(RecordWriter& record) const {
  const Volume& v = *volume_;
  // The samples first: at the record's start (16-aligned in a part file) + 8,
  // so a reader can keep them in the mapping.
  record.array<float>(std::span<const float>(samples_.data(), samples_.size()));
  for (int a = 0; a < 3; ++a) record.pod(int32_t(v.dims[a]));
  for (int a = 0; a < 3; ++a) record.pod(int32_t(lo_[a]));
  for (int a = 0; a < 3; ++a) record.pod(int32_t(hi_[a]));
  record.pod(v.gridFromWorld);
  record.pod(v.sigmaA);
  record.pod(v.sigmaS);
  record.pod(v.g);
  record.pod(uint8_t(v.normalise ? 1 : 0));
  record.pod(v.valueLo);
  record.pod(v.valueRange);
  record.pod(uint8_t(v.transfer ? 1 : 0));
  if (v.transfer) {
    record.array<TransferFunction::ColorPoint>(v.transfer->colors());
    record.array<TransferFunction::OpacityPoint>(v.transfer->opacities());
    record.pod(v.transfer->scale());
  }
}

std::shared_ptr<const Shape> VolumeBrick::read(RecordReader& record) {
  SharedArray<float> samples = record.sharedArray<float>();
  auto volume = std::make_shared<Volume>();
  std::array<int, 3> lo, hi;
  for (int a = 0; a < 3; ++a) volume->dims[a] = record.pod<int32_t>();
  for (int a = 0; a < 3; ++a) lo[a] = record.pod<int32_t>();
  for (int a = 0; a < 3; ++a) hi[a] = record.pod<int32_t>();
  volume->gridFromWorld = record.pod<Affine3f>();
  volume->sigmaA = record.pod<Vec3f>();
  volume->sigmaS = record.pod<Vec3f>();
  volume->g = record.pod<float>();
  volume->normalise = record.pod<uint8_t>() != 0;
  volume->valueLo = record.number();
  volume->valueRange = record.number();
  if (!(volume->valueRange >= 0) || !std::isfinite(volume->valueRange))
    record.fail("a volume brick's value range is negative or not finite");
  const uint8_t hasTransfer = record.pod<uint8_t>();
  try {
    if (hasTransfer) {
      auto colors = record.array<TransferFunction::ColorPoint>();
      auto opacities = record.array<TransferFunction::OpacityPoint>();
      const float scale = record.pod<float>();
      volume->transfer =
          std::make_shared<TransferFunction>(std::move(colors), std::move(opacities), scale);
    }
  } catch (const std::invalid_argument& e) {
    record.fail(e.what());
  }
  const Affine3f& m = volume->gridFromWorld;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(m.l[r][c])) record.fail("a volume brick's placement is not finite");
  if (!std::isfinite(m.determinant()) || m.determinant() == 0 || !isFinite(m.t))
    record.fail("a volume brick's placement is not invertible");
  if (!isFinite(volume->sigmaA) || !isFinite(volume->sigmaS) || !(volume->g > -1) ||
      !(volume->g < 1) ||
      !(min(volume->sigmaA, volume->sigmaS) == max(min(volume->sigmaA, volume->sigmaS), Vec3f(0))))
    record.fail("a volume brick's coefficients are out of range");
  try {
    return std::make_shared<VolumeBrick>(std::move(volume), lo, hi, std::move(samples));
  } catch (const InputError& e) {
    record.fail(e.what());
  }
}

std::string VolumeBrick::describe() const {
  const std::array<int, 3>& n = volume_->dims;
  return fmt::format("volume brick {}x{}x{} at ({}, {}, {}) of {}x{}x{}", hi_[0] - lo_[0],
                     hi_[1] - lo_[1], hi_[2] - lo_[2], lo_[0], lo_[1], lo_[2], n[0], n[1], n[2]);
}

// ------------------------------------------------------------ bricking

namespace {

// Whether medium `m` of `scene` fills its own box (see brickVolumes).
bool fillsItsBox(const Scene& scene, int32_t m) {
  const Medium& medium = scene.media[size_t(m)];
  if (!medium.density || medium.rgb || medium.cloud || medium.emits() || medium.temperature ||
      medium.emissionScale)
    return false;
  const Vec3f sigmaT = medium.sigmaT();
  if (!medium.transfer && !(sigmaT.x == sigmaT.y && sigmaT.y == sigmaT.z)) return false;
  for (const Mesh& mesh : scene.meshes)
    if (mesh.media.inside == m || mesh.media.outside == m) return false;
  const MediumBoundary* boundary = nullptr;
  for (const MediumBoundary& b : scene.mediumBoundaries) {
    if (b.media.inside != m && b.media.outside != m) continue;
    if (boundary) return false;
    boundary = &b;
  }
  if (!boundary || !(boundary->media == MediumInterface{m, kNoMedium})) return false;
  const Box3f box = medium.gridFromWorld.inverse().transformBox({Vec3f(0), Vec3f(1)});
  const Box3f bounds = boundary->mesh.bounds();
  const float tolerance = 1e-4f * std::max(maxComponent(box.size()), 1e-30f);
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(box.lower[a] - bounds.lower[a]) <= tolerance &&
          std::abs(box.upper[a] - bounds.upper[a]) <= tolerance))
      return false;
  return true;
}

}  // namespace

int autoBrickVoxels(std::array<int, 3> dims) {
  if (uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]) < kAutoBrickSamples) return 0;
  const int side = std::max({dims[0], dims[1], dims[2]}) / 16;
  return std::clamp(side / 8 * 8, 32, 128);
}

size_t brickVolumes(Scene& scene, int brickVoxels, const VolumeLook& look) {
  if (brickVoxels < 1 && brickVoxels != kAutoBricks)
    throw InputError(fmt::format("volume bricks of {} voxels: expected 1 or more", brickVoxels));
  std::vector<int32_t> renumbered(scene.media.size());
  std::vector<Medium> kept;
  int32_t material = -1;
  size_t bricked = 0;
  for (int32_t m = 0; m < int32_t(scene.media.size()); ++m) {
    const DensityGrid* density = scene.media[size_t(m)].density.get();
    const int side = brickVoxels != kAutoBricks ? brickVoxels
                     : density ? autoBrickVoxels({density->nx(), density->ny(), density->nz()})
                               : 0;
    if (side < 1 || !fillsItsBox(scene, m)) {
      renumbered[size_t(m)] = int32_t(kept.size());
      kept.push_back(std::move(scene.media[size_t(m)]));
      continue;
    }
    renumbered[size_t(m)] = kNoMedium;
    ++bricked;
    const Medium& medium = scene.media[size_t(m)];
    const DensityGrid& grid = *medium.density;
    auto volume = std::make_shared<VolumeBrick::Volume>();
    volume->dims = {grid.nx(), grid.ny(), grid.nz()};
    volume->gridFromWorld = medium.gridFromWorld;
    volume->sigmaA = medium.sigmaA;
    volume->sigmaS = medium.sigmaS;
    volume->g = medium.g;
    volume->transfer = medium.transfer;
    if (medium.transfer && !look.isDefault()) {
      try {
        volume->transfer =
            std::make_shared<const TransferFunction>(restyled(*medium.transfer, look));
      } catch (const std::invalid_argument& e) {
        throw InputError(e.what());
      }
    }
    if (material < 0) {
      Material none;
      none.name = "volume";
      material = scene.addMaterial(none);
    }
    std::array<int, 3> lo, hi;
    for (lo[2] = 0; lo[2] < grid.nz(); lo[2] += side)
      for (lo[1] = 0; lo[1] < grid.ny(); lo[1] += side)
        for (lo[0] = 0; lo[0] < grid.nx(); lo[0] += side) {
          for (int a = 0; a < 3; ++a) hi[a] = std::min(lo[a] + side, volume->dims[a]);
          std::shared_ptr<VolumeBrick> brick = VolumeBrick::cut(volume, grid, lo, hi);
          if (!(brick->majorant() > 0)) continue;  // it never collides
          scene.addSingleInstanceGeometry(
              {fmt::format("{} brick {},{},{}", medium.name, lo[0], lo[1], lo[2]), material,
               std::move(brick)});
        }
  }
  scene.media = std::move(kept);  // (every medium was moved into `kept`)
  if (bricked == 0) return 0;
  auto renumber = [&](int32_t& m) {
    if (m != kNoMedium) m = renumbered[size_t(m)];
  };
  std::vector<MediumBoundary> boundaries;
  for (MediumBoundary& b : scene.mediumBoundaries) {
    renumber(b.media.inside);
    renumber(b.media.outside);
    if (b.media.isTransition()) boundaries.push_back(std::move(b));
  }
  scene.mediumBoundaries = std::move(boundaries);
  for (Mesh& mesh : scene.meshes) {
    renumber(mesh.media.inside);
    renumber(mesh.media.outside);
  }
  renumber(scene.cameraMedium);
  return bricked;
}

}  // namespace ferry
