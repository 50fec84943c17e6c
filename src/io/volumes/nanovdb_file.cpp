// NanoVDB files (.nvdb, pbrt-v4's nanovdb medium), through the headers of
// Debian's libnanovdb-dev: the only file that includes them. Zip-compressed
// grids are read (zlib); Blosc-compressed ones are an error naming the file.
#include <fmt/format.h>

#define NANOVDB_USE_ZIP
#include <nanovdb/NanoVDB.h>
#include <nanovdb/util/GridBuilder.h>
#include <nanovdb/util/IO.h>

#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "io/volumes/volume_files.h"
#include "media/medium.h"

namespace ferry {
namespace {

using Handle = nanovdb::GridHandle<nanovdb::HostBuffer>;

std::vector<Handle> readGrids(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw InputError(fmt::format("{}: no such file", path));
  try {
    return nanovdb::io::readGrids<nanovdb::HostBuffer, std::vector>(path);
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: not a NanoVDB file NanoVDB can read ({})", path, e.what()));
  }
}

// The float grid named `name` as a dense grid over its active box, each
// voxel a cell centred on its index (as readVdbDensity reads .vdb files).
VdbDensity densityOf(const std::vector<Handle>& handles, const std::string& path,
                     const std::string& name, bool required, uint64_t maxVoxels) {
  const nanovdb::FloatGrid* grid = nullptr;
  std::string names;
  for (const Handle& h : handles)
    if (const nanovdb::GridMetaData* meta = h.gridMetaData()) {
      names += (names.empty() ? "" : ", ") + std::string(meta->shortGridName());
      if (meta->shortGridName() == name) grid = h.grid<float>();
    }
  if (!grid && !required) return {};
  if (!grid)
    throw InputError(fmt::format("{}: no float grid named \"{}\" (grids: {})", path, name,
                                 names.empty() ? "none" : names));
  VdbDensity out;
  out.gridName = name;
  const nanovdb::CoordBBox active = grid->indexBBox();
  if (active.empty())
    throw InputError(fmt::format("{}: grid \"{}\" has no active voxels", path, name));
  const nanovdb::Coord lo = active.min();
  uint64_t side[3], count = 1;
  for (int a = 0; a < 3; ++a) {
    side[a] = uint64_t(int64_t(active.max()[a]) - int64_t(lo[a]) + 1);
    count = side[a] > maxVoxels / count ? maxVoxels + 1 : count * side[a];
  }
  if (count > maxVoxels)
    throw InputError(fmt::format(
        "{}: grid \"{}\" spans {} x {} x {} voxels, more than the {} read as a dense grid", path,
        name, side[0], side[1], side[2], maxVoxels));
  // Only scaled and translated grids keep a box.
  for (int a = 0; a < 3; ++a) {
    nanovdb::Vec3d axis(0, 0, 0);
    axis[a] = 1;
    const nanovdb::Vec3d d = grid->indexToWorldDir(axis);
    for (int b = 0; b < 3; ++b)
      if (b != a && std::abs(d[b]) > 1e-9 * std::abs(d[a]))
        throw InputError(fmt::format(
            "{}: grid \"{}\" is rotated or sheared; only scaled and translated grids are read",
            path, name));
    if (!(d[a] > 0))
      throw InputError(
          fmt::format("{}: grid \"{}\" is mirrored or flat; only positive scales "
                      "are read",
                      path, name));
  }
  std::vector<float> values(count);
  const auto accessor = grid->getAccessor();
  size_t i = 0;
  for (uint64_t z = 0; z < side[2]; ++z)
    for (uint64_t y = 0; y < side[1]; ++y)
      for (uint64_t x = 0; x < side[0]; ++x, ++i) {
        const nanovdb::Coord c(lo[0] + int(x), lo[1] + int(y), lo[2] + int(z));
        const float v = accessor.getValue(c);
        if (!std::isfinite(v) || v < 0)
          throw InputError(fmt::format(
              "{}: grid \"{}\" voxel ({}, {}, {}) is {}: densities must be finite and not "
              "negative",
              path, name, c[0], c[1], c[2], v));
        values[i] = v;
      }
  const nanovdb::Vec3d a =
      grid->indexToWorld(nanovdb::Vec3d(lo[0] - 0.5, lo[1] - 0.5, lo[2] - 0.5));
  const nanovdb::Vec3d b = grid->indexToWorld(nanovdb::Vec3d(
      lo[0] + double(side[0]) - 0.5, lo[1] + double(side[1]) - 0.5, lo[2] + double(side[2]) - 0.5));
  out.box = Box3f{{float(a[0]), float(a[1]), float(a[2])}, {float(b[0]), float(b[1]), float(b[2])}};
  try {
    out.grid =
        std::make_shared<DensityGrid>(int(side[0]), int(side[1]), int(side[2]), std::move(values));
  } catch (const std::invalid_argument& e) {
    throw InputError(fmt::format("{}: grid \"{}\": {}", path, name, e.what()));
  }
  return out;
}

}  // namespace

std::pair<VdbDensity, VdbDensity> readNanoVdbDensityAndTemperature(const std::string& path,
                                                                   uint64_t maxVoxels) {
  const std::vector<Handle> handles = readGrids(path);
  return {densityOf(handles, path, "density", true, maxVoxels),
          densityOf(handles, path, "temperature", false, maxVoxels)};
}

void writeNanoVdbFile(const std::string& path, const std::vector<NanoVdbGridToWrite>& grids) {
  std::vector<Handle> handles;
  for (const NanoVdbGridToWrite& g : grids) {
    nanovdb::GridBuilder<float> builder(0.0f);
    auto accessor = builder.getAccessor();
    size_t i = 0;
    for (int z = 0; z < g.dims[2]; ++z)
      for (int y = 0; y < g.dims[1]; ++y)
        for (int x = 0; x < g.dims[0]; ++x, ++i)
          if (g.values[i] != 0)
            accessor.setValue(nanovdb::Coord(g.origin[0] + x, g.origin[1] + y, g.origin[2] + z),
                              g.values[i]);
    handles.push_back(builder.getHandle<>(double(g.voxelSize), nanovdb::Vec3d(0, 0, 0), g.name));
  }
  try {
    std::ofstream os(path, std::ios::out | std::ios::binary | std::ios::trunc);
    if (!os) throw std::runtime_error("cannot open it for writing");
    for (const Handle& h : handles) nanovdb::io::writeGrid(os, h, nanovdb::io::Codec::ZIP);
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: {}", path, e.what()));
  }
}

Scene loadNanoVdbScene(const std::string& path) {
  const VdbDensity vdb = readNanoVdbDensityAndTemperature(path).first;
  const std::string name = std::filesystem::path(path).filename().string();
  Medium m = gridMedium(name, Vec3f(1), Vec3f(9), 0, vdb.grid, Affine3f::identity(), vdb.box);
  return volumeScene(name, std::move(m), vdb.box);
}

}  // namespace ferry
