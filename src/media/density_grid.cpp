#include "media/density_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace ferry {

DensityGrid::DensityGrid(int nx, int ny, int nz, std::vector<float> values)
    : nx_(nx), ny_(ny), nz_(nz), values_(std::move(values)) {
  if (nx <= 0 || ny <= 0 || nz <= 0)
    throw std::invalid_argument(
        fmt::format("grid dimensions {} x {} x {} must be positive", nx, ny, nz));
  const uint64_t count = uint64_t(nx) * uint64_t(ny) * uint64_t(nz);
  if (values_.size() != count)
    throw std::invalid_argument(fmt::format("{} x {} x {} = {} samples needed, {} given", nx, ny,
                                            nz, count, values_.size()));
  min_ = values_.empty() ? 0 : values_[0];
  max_ = min_;
  for (size_t i = 0; i < values_.size(); ++i) {
    const float v = values_[i];
    if (!std::isfinite(v) || v < 0)
      throw std::invalid_argument(fmt::format(
          "density sample {} (x {}, y {}, z {}) is {}: densities must be finite and "
          "not negative",
          i, i % size_t(nx), (i / size_t(nx)) % size_t(ny), i / (size_t(nx) * size_t(ny)), v));
    min_ = std::min(min_, v);
    max_ = std::max(max_, v);
  }
}

float DensityGrid::lookup(Vec3f p) const {
  const float sx = p.x * float(nx_) - 0.5f, sy = p.y * float(ny_) - 0.5f,
              sz = p.z * float(nz_) - 0.5f;
  const float fx = std::floor(sx), fy = std::floor(sy), fz = std::floor(sz);
  // Far outside (or NaN): nothing there.
  if (!(fx >= -1 && fy >= -1 && fz >= -1 && fx < float(nx_) && fy < float(ny_) && fz < float(nz_)))
    return 0;
  const int x = int(fx), y = int(fy), z = int(fz);
  const float dx = sx - fx, dy = sy - fy, dz = sz - fz;
  auto lerp = [](float t, float a, float b) { return (1 - t) * a + t * b; };
  float d00, d10, d01, d11;
  if (x >= 0 && y >= 0 && z >= 0 && x + 1 < nx_ && y + 1 < ny_ && z + 1 < nz_) {
    // Inside: the eight samples by offsets from the first (the same sums).
    const size_t row = size_t(nx_), slice = size_t(nx_) * size_t(ny_);
    const float* v = values_.data() + (size_t(z) * size_t(ny_) + size_t(y)) * row + size_t(x);
    d00 = lerp(dx, v[0], v[1]);
    d10 = lerp(dx, v[row], v[row + 1]);
    d01 = lerp(dx, v[slice], v[slice + 1]);
    d11 = lerp(dx, v[slice + row], v[slice + row + 1]);
  } else {
    d00 = lerp(dx, at(x, y, z), at(x + 1, y, z));
    d10 = lerp(dx, at(x, y + 1, z), at(x + 1, y + 1, z));
    d01 = lerp(dx, at(x, y, z + 1), at(x + 1, y, z + 1));
    d11 = lerp(dx, at(x, y + 1, z + 1), at(x + 1, y + 1, z + 1));
  }
  return lerp(dz, lerp(dy, d00, d10), lerp(dy, d01, d11));
}

float DensityGrid::meanIn(Vec3f lo, Vec3f hi) const {
  const int n[3] = {nx_, ny_, nz_};
  int first[3], last[3];
  for (int a = 0; a < 3; ++a) {
    first[a] = int(std::floor(lo[a] * float(n[a]) - 0.5f));
    last[a] = int(std::floor(hi[a] * float(n[a]) - 0.5f)) + 1;
  }
  double sum = 0;
  for (int z = first[2]; z <= last[2]; ++z)
    for (int y = first[1]; y <= last[1]; ++y)
      for (int x = first[0]; x <= last[0]; ++x) sum += at(x, y, z);
  const double count = double(last[0] - first[0] + 1) * double(last[1] - first[1] + 1) *
                       double(last[2] - first[2] + 1);
  return float(sum / count);
}

std::pair<float, float> DensityGrid::rangeIn(Vec3f lo, Vec3f hi) const {
  const int n[3] = {nx_, ny_, nz_};
  int first[3], last[3];
  bool outside = false;  // a sample outside the grid (0) takes part
  for (int a = 0; a < 3; ++a) {
    const float l = std::floor(lo[a] * float(n[a]) - 0.5f);
    const float h = std::floor(hi[a] * float(n[a]) - 0.5f) + 1;
    outside = outside || l < 0 || h > float(n[a] - 1);
    first[a] = int(std::clamp(l, 0.0f, float(n[a] - 1)));
    last[a] = int(std::clamp(h, 0.0f, float(n[a] - 1)));
  }
  float smallest = outside ? 0.0f : max_, largest = 0;
  for (int z = first[2]; z <= last[2]; ++z)
    for (int y = first[1]; y <= last[1]; ++y)
      for (int x = first[0]; x <= last[0]; ++x) {
        const float v = at(x, y, z);
        smallest = std::min(smallest, v);
        largest = std::max(largest, v);
      }
  return {smallest, largest};
}

}  // namespace ferry
