// The one file that includes OpenVDB (scripts/check_layering.py keeps it so).
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <type_traits>

#include <fmt/format.h>

#include "core/error.h"
#include "io/volumes/volume_files.h"

namespace ferry {

namespace {

void initializeOpenVdb() {
  static std::once_flag initialized;
  std::call_once(initialized, [] { openvdb::initialize(); });
}

openvdb::GridPtrVecPtr readGrids(const std::string& path) {
  initializeOpenVdb();
  if (!std::filesystem::exists(path)) throw InputError(fmt::format("{}: no such file", path));
  openvdb::GridPtrVecPtr grids;
  try {
    openvdb::io::File file(path);
    file.open(false);  // read everything now: no delayed loading from a file that may change
    grids = file.getGrids();
    file.close();
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: not a readable OpenVDB file ({})", path, e.what()));
  }
  return grids;
}

// The float grid `gridName` of `grids` (see readVdbDensity); with `required`
// false, a VdbDensity without a grid if there is none of that name.
VdbDensity densityOf(const openvdb::GridPtrVec& grids, const std::string& path,
                     const std::string& gridName, bool required, uint64_t maxVoxels) {
  openvdb::FloatGrid::Ptr grid;
  std::string names;
  for (const openvdb::GridBase::Ptr& g : grids) {
    names += (names.empty() ? "" : ", ") + g->getName() + " (" + g->valueType() + ")";
    auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
    if (!f) continue;
    const bool wanted =
        gridName.empty() ? (!grid || g->getName() == "density") : g->getName() == gridName;
    if (wanted && !(grid && grid->getName() == "density" && gridName.empty())) grid = f;
  }
  if (!grid && !required) return {};
  if (!grid)
    throw InputError(fmt::format("{}: no float grid{} (grids: {})", path,
                                 gridName.empty() ? "" : " named \"" + gridName + "\"",
                                 names.empty() ? "none" : names));
  const openvdb::math::Transform& transform = grid->transform();
  if (!transform.isLinear())
    throw InputError(
        fmt::format("{}: grid \"{}\" has a non-linear transform", path, grid->getName()));
  const openvdb::CoordBBox active = grid->evalActiveVoxelBoundingBox();
  VdbDensity out;
  out.gridName = grid->getName();
  if (active.empty())
    throw InputError(fmt::format("{}: grid \"{}\" has no active voxels", path, out.gridName));
  // (Counted in 64 bits: a sparse grid's box may span more than int32 voxels.)
  const openvdb::Coord lo = active.min();
  uint64_t side[3], count = 1;
  for (int a = 0; a < 3; ++a) {
    side[a] = uint64_t(int64_t(active.max()[a]) - int64_t(lo[a]) + 1);
    count = side[a] > maxVoxels / count ? maxVoxels + 1 : count * side[a];
  }
  if (count > maxVoxels)
    throw InputError(fmt::format(
        "{}: grid \"{}\" spans {} x {} x {} voxels, more than the {} read as a dense grid", path,
        out.gridName, side[0], side[1], side[2], maxVoxels));
  const openvdb::Coord dim{int(side[0]), int(side[1]), int(side[2])};
  // Every voxel of the box, active or not (the background where nothing is
  // stored), x fastest: OpenVDB's copyToDense, node by node, in parallel.
  std::vector<float> values(count);
  openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(active, values.data());
  openvdb::tools::copyToDense(*grid, dense);
  for (size_t i = 0; i < values.size(); ++i)
    if (const float v = values[i]; !std::isfinite(v) || v < 0) {
      const size_t x = i % size_t(dim.x()), y = i / size_t(dim.x()) % size_t(dim.y()),
                   z = i / (size_t(dim.x()) * size_t(dim.y()));
      throw InputError(fmt::format(
          "{}: grid \"{}\" voxel ({}, {}, {}) is {}: densities must be finite and not negative",
          path, out.gridName, lo.x() + int(x), lo.y() + int(y), lo.z() + int(z), v));
    }
  // Each voxel is a cell centred on its index: the box runs half a voxel
  // beyond the first and last centres. Only scale and translation keep it a box.
  const openvdb::Vec3d a =
      transform.indexToWorld(openvdb::Vec3d(lo.x() - 0.5, lo.y() - 0.5, lo.z() - 0.5));
  const openvdb::Vec3d b = transform.indexToWorld(
      openvdb::Vec3d(lo.x() + dim.x() - 0.5, lo.y() + dim.y() - 0.5, lo.z() + dim.z() - 0.5));
  const openvdb::math::Mat3d linear = transform.baseMap()->getAffineMap()->getMat4().getMat3();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (r != c && std::abs(linear(r, c)) > 1e-9 * std::abs(linear(r, r)))
        throw InputError(
            fmt::format("{}: grid \"{}\" is rotated or sheared; only scaled and "
                        "translated grids are read",
                        path, out.gridName));
  out.box = Box3f{
      {float(std::min(a.x(), b.x())), float(std::min(a.y(), b.y())), float(std::min(a.z(), b.z()))},
      {float(std::max(a.x(), b.x())), float(std::max(a.y(), b.y())),
       float(std::max(a.z(), b.z()))}};
  // (A negative scale mirrors the grid: its samples then run the other way.)
  if (linear(0, 0) < 0 || linear(1, 1) < 0 || linear(2, 2) < 0)
    throw InputError(fmt::format("{}: grid \"{}\" is mirrored; only positive scales are read", path,
                                 out.gridName));
  try {
    out.grid = std::make_shared<DensityGrid>(dim.x(), dim.y(), dim.z(), std::move(values));
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: grid \"{}\": {}", path, out.gridName, e.what()));
  }
  return out;
}

// The value a grid of type T stores for `v` (integers: toward zero, NaN 0,
// clamped to T's range, so that no conversion is undefined).
template <typename T>
T storedValue(float v) {
  if constexpr (std::is_floating_point_v<T>) {
    return T(v);
  } else {
    if (!(v == v)) return 0;
    using Limits = std::numeric_limits<T>;
    return T(std::clamp(double(v), double(Limits::lowest()), double(Limits::max())));
  }
}

template <typename GridT>
openvdb::GridBase::Ptr makeGrid(const VdbGridToWrite& g, const openvdb::math::Transform::Ptr& map) {
  using Value = typename GridT::ValueType;
  typename GridT::Ptr grid = GridT::create(storedValue<Value>(g.background));
  // (Unsafe: not registered with the tree, whose registry is a TBB
  // concurrent_hash_map that casts a flag value to a node pointer, undefined
  // behaviour UBSan stops at; nothing else touches the tree meanwhile.)
  auto accessor = grid->getUnsafeAccessor();
  for (const auto& [c, v] : g.voxels)
    accessor.setValue(openvdb::Coord(c[0], c[1], c[2]), storedValue<Value>(v));
  grid->setTransform(map);
  grid->setName(g.name);
  return grid;
}

}  // namespace

void writeVdbFile(const std::string& path, const std::vector<VdbGridToWrite>& grids) {
  initializeOpenVdb();
  try {
    openvdb::GridPtrVec out;
    for (const VdbGridToWrite& g : grids) {
      openvdb::math::Transform::Ptr map = openvdb::math::Transform::createLinearTransform(1.0);
      map->preScale(openvdb::Vec3d(g.scale[0], g.scale[1], g.scale[2]));
      map->postRotate(g.rotateZDegrees * (openvdb::math::pi<double>() / 180),
                      openvdb::math::Z_AXIS);
      map->postTranslate(openvdb::Vec3d(g.translation[0], g.translation[1], g.translation[2]));
      switch (g.type) {
        case VdbGridToWrite::Type::Float:
          out.push_back(makeGrid<openvdb::FloatGrid>(g, map));
          break;
        case VdbGridToWrite::Type::Double:
          out.push_back(makeGrid<openvdb::DoubleGrid>(g, map));
          break;
        case VdbGridToWrite::Type::Int32:
          out.push_back(makeGrid<openvdb::Int32Grid>(g, map));
          break;
      }
    }
    openvdb::io::File file(path);
    file.write(out);
    file.close();
  } catch (const std::exception& e) {
    throw InputError(
        fmt::format("{}: cannot write the grids as an OpenVDB file ({})", path, e.what()));
  }
}

VdbDensity readVdbDensity(const std::string& path, const std::string& gridName,
                          uint64_t maxVoxels) {
  return densityOf(*readGrids(path), path, gridName, true, maxVoxels);
}

std::pair<VdbDensity, VdbDensity> readVdbDensityAndTemperature(const std::string& path,
                                                               uint64_t maxVoxels) {
  const openvdb::GridPtrVecPtr grids = readGrids(path);
  return {densityOf(*grids, path, "density", true, maxVoxels),
          densityOf(*grids, path, "temperature", false, maxVoxels)};
}

Scene loadVdbScene(const std::string& path) {
  const VdbDensity vdb = readVdbDensity(path);
  const std::string name = std::filesystem::path(path).filename().string();
  Medium m = gridMedium(name, Vec3f(1), Vec3f(9), 0, vdb.grid, Affine3f::identity(), vdb.box);
  return volumeScene(name, std::move(m), vdb.box);
}

}  // namespace ferry
