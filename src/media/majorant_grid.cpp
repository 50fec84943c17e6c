#include "media/majorant_grid.h"

#include <stdexcept>
#include <tuple>

namespace ferry {

MajorantGrid::MajorantGrid(const DensityGrid& grid, int cells)
    : MajorantGrid(
          grid,
          [](float lo, float hi, float) {
            return std::pair{hi, Vec3f(lo)};
          },
          cells) {}

MajorantGrid::MajorantGrid(const DensityGrid& grid, const Extinction& extinction, int cells) {
  res_[0] = std::clamp(grid.nx(), 1, cells);
  res_[1] = std::clamp(grid.ny(), 1, cells);
  res_[2] = std::clamp(grid.nz(), 1, cells);
  values_.resize(size_t(res_[0]) * size_t(res_[1]) * size_t(res_[2]));
  controls_.resize(values_.size());
  ranges_.resize(values_.size());
  for (int z = 0; z < res_[2]; ++z)
    for (int y = 0; y < res_[1]; ++y)
      for (int x = 0; x < res_[0]; ++x) {
        const Vec3f lo{float(x) / float(res_[0]), float(y) / float(res_[1]),
                       float(z) / float(res_[2])};
        const Vec3f hi{float(x + 1) / float(res_[0]), float(y + 1) / float(res_[1]),
                       float(z + 1) / float(res_[2])};
        const auto [smallest, largest] = grid.rangeIn(lo, hi);
        const float mean = std::clamp(grid.meanIn(lo, hi), smallest, largest);
        ranges_[index(x, y, z)] = {smallest, largest, mean};
        const auto [majorant, control] = extinction(smallest, largest, mean);
        values_[index(x, y, z)] = majorant;
        controls_[index(x, y, z)] = control;
      }
}

MajorantGrid::MajorantGrid(int rx, int ry, int rz, std::vector<float> majorants)
    : values_(std::move(majorants)), controls_(values_.size()) {
  res_[0] = rx, res_[1] = ry, res_[2] = rz;
  if (rx < 1 || ry < 1 || rz < 1 || values_.size() != size_t(rx) * size_t(ry) * size_t(rz))
    throw std::invalid_argument("majorant cells: the counts do not match the values");
}

MajorantGrid::MajorantGrid(float majorant, Vec3f control) : values_{majorant}, controls_{control} {}

MajorantGrid::MajorantGrid(const MajorantGrid& cells, const Extinction& extinction)
    : values_(cells.values_.size()), controls_(cells.values_.size()), ranges_(cells.ranges_) {
  std::copy(cells.res_, cells.res_ + 3, res_);
  for (size_t i = 0; i < ranges_.size(); ++i)
    std::tie(values_[i], controls_[i]) = extinction(ranges_[i].lo, ranges_[i].hi, ranges_[i].mean);
}

}  // namespace ferry
