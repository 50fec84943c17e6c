// One brick of a grid volume: the samples of a box of the grid's cells and
// the one-sample ghost layer its trilinear lookups read, as a geometry the
// partitioners place, the proxies bound and part files store like any
// other, so a volume is spread over ranks brick by brick.
//
// A crossing is a collision in the medium, sampled by delta tracking with
// random numbers that are a function of the ray and the brick alone, so the
// nearest collision over the bricks a ray passes is the same in any order,
// on any rank, however often asked. Shadow rays ask the same question
// (transmittance 0 or 1). The extinction must be grey; shading scatters at
// a collision by the phase function, weighed by the albedo there.
// docs/volumes.md, "Bricks across ranks", says why.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "core/shared_array.h"
#include "media/majorant_grid.h"
#include "media/medium.h"
#include "media/transfer_function.h"
#include "media/volume_look.h"
#include "scene/shape.h"

namespace ferry {

struct Scene;

// Majorant cells of a brick: one per this many voxels along each axis.
constexpr int kBrickMajorantVoxels = 8;

class VolumeBrick final : public Shape {
 public:
  // What a volume's bricks share: the grid's size and placement and how its
  // values become extinction and albedo.
  struct Volume {
    std::array<int, 3> dims{};               // the whole grid's samples along x, y, z
    Affine3f gridFromWorld;                  // world to the whole grid's unit cube
    Vec3f sigmaA{0, 0, 0}, sigmaS{0, 0, 0};  // at value 1 (no transfer function)
    float g = 0;
    std::shared_ptr<const TransferFunction> transfer;  // null: sigma x value
    // Samples held as a file has them (float32 in a mapping), each mapped to
    // [0, 1] where it is read: clamp((v - valueLo) / valueRange, 0, 1), 0
    // without a range (a raw: volume's normalisation, the same floats).
    bool normalise = false;
    float valueLo = 0, valueRange = 1;
    float normalised(float v) const {
      return valueRange > 0 ? std::clamp((v - valueLo) / valueRange, 0.0f, 1.0f) : 0.0f;
    }
  };

  // The cells [lo, hi) of `volume`'s grid (voxel boundaries along each
  // axis), with `samples` the grid's samples [max(lo - 1, 0), min(hi, n - 1)]
  // (x fastest). Throws InputError if they do not fit together.
  // `samples` may stay in a part file's mapping (SharedArray).
  VolumeBrick(std::shared_ptr<const Volume> volume, std::array<int, 3> lo, std::array<int, 3> hi,
              SharedArray<float> samples);
  // The brick of `grid` (the whole volume's samples) over the cells [lo, hi).
  static std::shared_ptr<VolumeBrick> cut(std::shared_ptr<const Volume> volume,
                                          const DensityGrid& grid, std::array<int, 3> lo,
                                          std::array<int, 3> hi);

  std::string_view kind() const override { return "volume-brick"; }
  uint32_t primitiveCount() const override { return 1; }
  Box3f primitiveBounds(uint32_t primitive) const override;
  uint64_t bytes() const override;
  bool intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                 float& t, Vec2f& uv) const override;
  bool intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                 float& t, Vec2f& uv, ShapeWork& work) const override;
  ShapeSurface surface(uint32_t primitive, Vec2f uv) const override;
  bool isVolume() const override { return true; }
  Vec3f volumeAlbedo(uint32_t primitive, Vec3f point) const override;
  float volumePhaseG() const override { return volume_->g; }
  void write(RecordWriter& record) const override;
  std::string describe() const override;
  static std::shared_ptr<const Shape> read(RecordReader& record);

  // The value at `unit` (the whole grid's unit cube), as DensityGrid::lookup
  // gives it bit for bit for any point of this brick's cells.
  float lookup(Vec3f unit) const;
  // The extinction at a value (grey).
  float extinction(float value) const;
  // The largest extinction anywhere in the brick (0: it never collides).
  float majorant() const { return largest_; }
  const Volume& volume() const { return *volume_; }
  const std::array<int, 3>& lo() const { return lo_; }
  const std::array<int, 3>& hi() const { return hi_; }
  // Whether the samples are read in place from a mapping (a part file).
  bool samplesShared() const { return samples_.isShared(); }
  // Draws the brick through `volume`'s transfer function (a copy of its own
  // volume restyled: the same grid, placement and value mapping; throws
  // InputError otherwise). The majorants are rebuilt from the value range
  // kept per cell, without a pass over the samples, and equal those of a
  // brick made with that volume. Not while a ray crosses the brick.
  void restyle(std::shared_ptr<const Volume> volume);

 private:
  float sample(int x, int y, int z) const;
  // The majorant of a cell whose lookups give values in [low, high].
  static float cellMajorant(const Volume& v, float low, float high);
  std::shared_ptr<const Volume> volume_;
  std::array<int, 3> lo_, hi_;        // cells
  std::array<int, 3> first_, count_;  // the samples held
  SharedArray<float> samples_;
  std::unique_ptr<MajorantGrid> majorants_;      // over the brick's cells
  std::vector<std::pair<float, float>> ranges_;  // each majorant cell's values, [low, high]
  float largest_ = 0;
  Vec3f unitLo_, unitSize_;  // the brick's cells in the grid's unit cube
  uint32_t seed_ = 0;        // of its random numbers: its place in the grid
};

// Replaces every grid medium of `scene` that fills its own box (its only
// boundary is that box, with the medium inside and nothing outside; no
// other surface or the camera is in it) and has a grey extinction, no
// emission and no rgb or cloud density, by bricks of `brickVoxels` cells a
// side: geometries of one instance each. Bricks that can never collide (a
// majorant of 0) are left out; a transfer function is restyled by `look`
// first (a brick's look is fixed when it is made). Returns
// the number of media bricked. Other media stay as they are.
// `brickVoxels` kAutoBricks chooses each volume's size by autoBrickVoxels.
size_t brickVolumes(Scene& scene, int brickVoxels, const VolumeLook& look = {});

// --volume-bricks auto (the default): every grid of at least
// kAutoBrickSamples samples is bricked, in bricks of a sixteenth of its
// largest side (at least 32 voxels, at most 128, a multiple of 8), about
// 4,096 bricks for a cube; smaller grids stay whole. A function of the grid
// alone, never of the rank count: a brick's random numbers depend on its
// cells, so the image is the same on any number of ranks.
constexpr int kAutoBricks = -1;
constexpr uint64_t kAutoBrickSamples = uint64_t(1) << 24;  // 64 MiB of float32
int autoBrickVoxels(std::array<int, 3> dims);

}  // namespace ferry
