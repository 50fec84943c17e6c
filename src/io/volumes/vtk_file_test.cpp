// VTK files (io/volumes/vtk_file.cpp): a .vti is the volume a raw: file of
// the same samples is; its arrays are chosen by name; a .vtp's points are
// spheres; bad files are errors naming the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"
#include "io/scene_loader.h"
#include "io/volumes/volume_files.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

std::string tempFile(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / fmt::format("ferry-vtk-{}-{}", getpid(), name);
  std::ofstream(path) << text;
  return path.string();
}

// 3 x 2 x 2 points: density i - 2 (point i), velocity (i, 0, 0), and one
// cell array (2 x 1 x 1 cells).
const float kDensity[12] = {-2, -1, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
std::string imageXml(const std::string& scalars = "density") {
  std::string density, velocity;
  for (int i = 0; i < 12; ++i) {
    density += fmt::format("{} ", kDensity[i]);
    velocity += fmt::format("{} 0 0 ", i);
  }
  return fmt::format(
      R"(<?xml version="1.0"?>
<VTKFile type="ImageData" version="0.1" byte_order="LittleEndian">
  <ImageData WholeExtent="0 2 0 1 0 1" Origin="1 2 3" Spacing="0.5 0.5 0.25">
    <Piece Extent="0 2 0 1 0 1">
      <PointData Scalars="{}">
        <DataArray type="Float32" Name="density" format="ascii">{}</DataArray>
        <DataArray type="Float64" Name="velocity" NumberOfComponents="3" format="ascii">{}</DataArray>
      </PointData>
      <CellData>
        <DataArray type="Int32" Name="material" format="ascii">4 8</DataArray>
      </CellData>
    </Piece>
  </ImageData>
</VTKFile>
)",
      scalars, density, velocity);
}

TEST(VtkFile, AnImageIsTheVolumeOfARawFileOfItsSamples) {
  const std::string vti = tempFile("a.vti", imageXml());
  const std::string raw =
      (fs::temp_directory_path() / fmt::format("ferry-vtk-{}.raw", getpid())).string();
  std::ofstream(raw, std::ios::binary)
      .write(reinterpret_cast<const char*>(kDensity), sizeof(kDensity));
  // A raw: sample is the centre of a cell from `origin`; a VTK point is at origin + i spacing.
  const Scene fromRaw = loadScene(fmt::format(
      "raw:{}?dims=3,2,2&format=float32&spacing=0.5,0.5,0.25&origin=0.75,1.75,2.875", raw));
  const Scene fromVtk = loadScene(vti);
  fs::remove(vti);
  fs::remove(raw);
  ASSERT_EQ(fromVtk.media.size(), 1u);
  const Medium& a = fromRaw.media[0];
  const Medium& b = fromVtk.media[0];
  EXPECT_EQ(a.density->values(), b.density->values());
  EXPECT_EQ(b.density->values().front(), 0.0f);
  EXPECT_EQ(b.density->values().back(), 1.0f);
  EXPECT_EQ(a.transfer->scale(), b.transfer->scale());
  for (float t : {0.0f, 0.3f, 1.0f})
    EXPECT_EQ(a.gridFromWorld.transformPoint(Vec3f(t + 1, 2, 3)),
              b.gridFromWorld.transformPoint(Vec3f(t + 1, 2, 3)));
  EXPECT_NE(b.name.find("'density' [-2, 9]"), std::string::npos) << b.name;
}

TEST(VtkFile, ArraysAreChosenByNameOrTheActiveScalars) {
  const std::string vti = tempFile("b.vti", imageXml("velocity"));
  const Scene active = loadScene(vti);  // the active scalars: velocity, by magnitude
  EXPECT_NE(active.media[0].name.find("'velocity' [0, 11] (magnitude)"), std::string::npos)
      << active.media[0].name;
  LoadOptions cells;
  cells.field = "material";
  const Scene byCell = loadScene(vti, cells);
  EXPECT_EQ(byCell.media[0].density->nx(), 2);
  EXPECT_EQ(byCell.media[0].density->values(), (std::vector<float>{0, 1}));
  LoadOptions missing;
  missing.field = "temperature";
  try {
    loadScene(vti, missing);
    ADD_FAILURE() << "an array that is not there was taken";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(vti), std::string::npos) << m;
    EXPECT_NE(m.find("point arrays: density, velocity; cell arrays: material"), std::string::npos)
        << m;
  }
  fs::remove(vti);
}

TEST(VtkFile, PointsWithARadiusAreSpheres) {
  const std::string vtp = tempFile("c.vtp", R"(<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
  <PolyData>
    <Piece NumberOfPoints="3" NumberOfVerts="0" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="0">
      <PointData>
        <DataArray type="Float32" Name="radius" format="ascii">0.1 0.2 0.3</DataArray>
        <DataArray type="Float32" Name="zero" format="ascii">0 0 0</DataArray>
      </PointData>
      <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 0 1 0</DataArray></Points>
    </Piece>
  </PolyData>
</VTKFile>
)");
  const Scene scene = loadScene(vtp);
  ASSERT_EQ(scene.geometries.size(), 1u);
  EXPECT_EQ(scene.geometries[0].shape->kind(), "spheres");
  EXPECT_EQ(scene.geometries[0].shape->primitiveCount(), 3u);
  const Box3f last = scene.geometries[0].shape->primitiveBounds(2);
  EXPECT_FLOAT_EQ(last.upper.y, 1.3f);
  LoadOptions zero;
  zero.field = "zero";
  EXPECT_THROW(loadScene(vtp, zero), InputError);
  fs::remove(vtp);
}

TEST(VtkFile, BadFilesAreErrorsNamingThem) {
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"d.vti", "<VTKFile"},
                                   {"e.vti", "not xml at all"},
                                   {"f.vti", imageXml().substr(0, 400)},
                                   {"g.vtp", imageXml()}}) {
    const std::string path = tempFile(name, text);
    try {
      loadScene(path);
      ADD_FAILURE() << name << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    fs::remove(path);
  }
}

}  // namespace
}  // namespace ferry
