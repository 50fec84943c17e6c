// A density on a regular grid over the unit cube, looked up as pbrt looks up
// its grid media (pbrt-v3's GridDensityMedium, pbrt-v4's SampledGrid): sample
// (x, y, z) sits at the centre of its voxel, values are interpolated
// trilinearly, and every sample outside the grid is 0 (so the density fades
// to 0 within half a voxel of the unit cube's faces).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/math.h"

namespace ferry {

class DensityGrid {
 public:
  DensityGrid() = default;
  // `values`: nx * ny * nz samples, x fastest, then y, then z (pbrt's
  // order). Throws std::invalid_argument if the counts do not match, a count
  // is not positive, or a value is negative or not finite (the message says
  // which sample).
  DensityGrid(int nx, int ny, int nz, std::vector<float> values);

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int nz() const { return nz_; }
  const std::vector<float>& values() const { return values_; }
  size_t bytes() const { return values_.size() * sizeof(float); }
  float minValue() const { return min_; }
  float maxValue() const { return max_; }

  // The density at `p` in the unit cube's coordinates (0 outside it).
  float lookup(Vec3f p) const;
  // The smallest and largest density lookup() can return anywhere in the box
  // [lo, hi] (unit-cube coordinates): over the samples a lookup there
  // interpolates (pbrt-v4's SampledGrid::MaxValue); the smallest is 0 where
  // the box comes within half a voxel of the grid's faces.
  std::pair<float, float> rangeIn(Vec3f lo, Vec3f hi) const;
  // The mean of the samples those lookups interpolate (outside ones as 0).
  float meanIn(Vec3f lo, Vec3f hi) const;

 private:
  float at(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= nx_ || y >= ny_ || z >= nz_) return 0;
    return values_[(size_t(z) * size_t(ny_) + size_t(y)) * size_t(nx_) + size_t(x)];
  }
  int nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<float> values_;
  float min_ = 0, max_ = 0;
};

}  // namespace ferry
