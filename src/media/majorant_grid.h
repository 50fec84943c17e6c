// Cells over a grid medium's unit cube (one per voxel along each axis, at
// most 32), each holding the largest extinction any channel can have
// inside it (the majorant that delta and ratio tracking step against, cell
// by cell, so thin regions cost few steps and empty cells none: pbrt-v4's
// MajorantGrid and DDA iterator) and each channel's control (an extinction
// near the cell's mean, which residual ratio tracking takes out in closed
// form).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "core/math.h"
#include "media/density_grid.h"

namespace ferry {

// Cells per axis at most (docs/volumes.md, "Shadow rays": finer cells, lower
// shadow-ray error at equal time; at most 7 MiB a medium).
constexpr int kMajorantCells = 32;

class MajorantGrid {
 public:
  // For the grid's values in [lo, hi] (what a cell's lookups can return),
  // `mean` their samples' mean: the largest extinction of any channel, and
  // each channel's control (an extinction near the cell's typical one, at
  // most the majorant).
  using Extinction = std::function<std::pair<float, Vec3f>(float lo, float hi, float mean)>;
  // One cell per voxel along each axis, at most `cells`.
  MajorantGrid(const DensityGrid& grid, const Extinction& extinction, int cells = kMajorantCells);
  // The grid's values themselves as the extinction.
  explicit MajorantGrid(const DensityGrid& grid, int cells = kMajorantCells);
  // `rx` x `ry` x `rz` cells over the cube with these majorants, x fastest
  // (controls 0): a bound made elsewhere (a volume brick's cells).
  MajorantGrid(int rx, int ry, int rz, std::vector<float> majorants);
  // One cell over the whole cube (pbrt-v4's cloud: a bound known without a grid).
  MajorantGrid(float majorant, Vec3f control);
  // The cells of `cells` (made over a grid) with another extinction, from the
  // value ranges it kept: no pass over the grid (a transfer function's change).
  MajorantGrid(const MajorantGrid& cells, const Extinction& extinction);

  int cells(int axis) const { return res_[axis]; }
  float at(int x, int y, int z) const { return values_[index(x, y, z)]; }
  Vec3f controlAt(int x, int y, int z) const { return controls_[index(x, y, z)]; }

  // Calls visit(tEnter, tExit, majorant, control) for every cell the ray o + t d
  // (unit-cube coordinates) passes within [t0, t1], in order, until visit
  // returns false. [t0, t1] must already lie within the unit cube.
  template <typename Visit>
  void walk(Vec3f o, Vec3f d, float t0, float t1, Visit&& visit) const;

 private:
  size_t index(int x, int y, int z) const {
    return (size_t(z) * size_t(res_[1]) + size_t(y)) * size_t(res_[0]) + size_t(x);
  }
  int res_[3] = {1, 1, 1};
  std::vector<float> values_;
  std::vector<Vec3f> controls_;
  struct Values {
    float lo, hi, mean;
  };
  std::vector<Values> ranges_;  // each cell's values (empty: none kept)
};

// Where the ray o + t d meets the unit cube, clipped to [tMin, tMax]; false if
// it misses.
inline bool clipToUnitCube(Vec3f o, Vec3f d, float& tMin, float& tMax) {
  for (int a = 0; a < 3; ++a) {
    const float inv = 1 / d[a];
    float tNear = (0 - o[a]) * inv, tFar = (1 - o[a]) * inv;
    if (tNear > tFar) std::swap(tNear, tFar);
    // NaN (d[a] == 0 with o on a face) leaves the bounds as they are.
    if (tNear > tMin) tMin = tNear;
    if (tFar < tMax) tMax = tFar;
    if (d[a] == 0 && (o[a] < 0 || o[a] > 1)) return false;
  }
  return tMin < tMax;
}

template <typename Visit>
void MajorantGrid::walk(Vec3f o, Vec3f d, float t0, float t1, Visit&& visit) const {
  int cell[3], step[3], stop[3];
  float next[3], delta[3];
  const Vec3f p = o + d * t0;
  for (int a = 0; a < 3; ++a) {
    const float r = float(res_[a]);
    cell[a] = std::clamp(int(p[a] * r), 0, res_[a] - 1);
    if (d[a] > 0) {
      step[a] = 1;
      stop[a] = res_[a];
      next[a] = t0 + (float(cell[a] + 1) / r - p[a]) / d[a];
      delta[a] = 1 / (r * d[a]);
    } else if (d[a] < 0) {
      step[a] = -1;
      stop[a] = -1;
      next[a] = t0 + (float(cell[a]) / r - p[a]) / d[a];
      delta[a] = -1 / (r * d[a]);
    } else {
      step[a] = 0;
      stop[a] = -2;
      next[a] = kInfinity;
      delta[a] = kInfinity;
    }
  }
  float t = t0;
  for (;;) {
    // The axis whose cell boundary comes first.
    const int a = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
    const float exit = std::min(next[a], t1);
    const size_t i = index(cell[0], cell[1], cell[2]);
    if (exit > t && !visit(t, exit, values_[i], controls_[i])) return;
    if (next[a] >= t1) return;
    t = exit;
    cell[a] += step[a];
    if (cell[a] == stop[a]) return;
    next[a] += delta[a];
  }
}

}  // namespace ferry
