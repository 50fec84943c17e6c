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
#include "shapes/unstructured_volume.h"

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

TEST(VtkFile, TheSceneListsEveryArrayWithItsRangeAndTheOneRendered) {
  const std::string vti = tempFile("f.vti", imageXml());
  LoadOptions velocity;
  velocity.field = "velocity";
  const Scene byDefault = loadScene(vti), byName = loadScene(vti, velocity);
  fs::remove(vti);
  ASSERT_EQ(byDefault.volumeFields.size(), 3u);
  const VolumeField& density = byDefault.volumeFields[0];
  const VolumeField& speed = byDefault.volumeFields[1];
  const VolumeField& material = byDefault.volumeFields[2];
  EXPECT_EQ(density.name, "density");
  EXPECT_FALSE(density.atCells);
  EXPECT_EQ(density.lo, -2);
  EXPECT_EQ(density.hi, 9);
  EXPECT_EQ(speed.name, "velocity");
  EXPECT_EQ(speed.components, 3);
  EXPECT_EQ(speed.lo, 0);  // by magnitude
  EXPECT_EQ(speed.hi, 11);
  EXPECT_EQ(material.name, "material");
  EXPECT_TRUE(material.atCells);
  EXPECT_EQ(material.lo, 4);
  EXPECT_EQ(material.hi, 8);
  EXPECT_EQ(byDefault.volumeField, 0);
  EXPECT_EQ(byName.volumeField, 1);
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
  for (const auto& [name, text] :
       {std::pair<std::string, std::string>{"d.vti", "<VTKFile"},
        {"e.vti", "not xml at all"},
        {"f.vti", imageXml().substr(0, 400)},
        {"g.vtp", imageXml()},
        {"h.vtu", imageXml()},
        {"i.vtk", "# vtk DataFile Version 3.0\nnot a grid\nASCII\nDATASET POLYDATA\n"},
        {"j.pvtu", "<VTKFile type=\"PUnstructuredGrid\"><PUnstructuredGrid>"},
        {"k.pvtu", imageXml()},
        {"l.pvtu", "<VTKFile><PUnstructuredGrid></PUnstructuredGrid></VTKFile>"},
        {"m.pvtu", "<VTKFile><PUnstructuredGrid><Piece/></PUnstructuredGrid></VTKFile>"},
        {"n.pvtu",
         "<VTKFile><PUnstructuredGrid><Piece "
         "Source=\"nowhere.vtu\"/></PUnstructuredGrid></VTKFile>"},
        {"o.pvti", "<VTKFile type=\"PImageData\"><PImageData>"},
        {"p.pvti", imageXml()},
        {"q.pvti",
         "<VTKFile><PImageData><Piece Extent=\"0 1 0 1 0 1\" Source=\"a.vti\"/>"
         "</PImageData></VTKFile>"},
        {"r.pvti",
         "<VTKFile><PImageData WholeExtent=\"0 1 0 1 0 1\"><PPointData>"
         "<PDataArray Name=\"T\"/></PPointData></PImageData></VTKFile>"},
        {"s.pvti",
         "<VTKFile><PImageData WholeExtent=\"0 1 0 1 0 1\"><PPointData>"
         "<PDataArray Name=\"T\"/></PPointData><Piece Extent=\"0 1 0 1 0 1\"/>"
         "</PImageData></VTKFile>"},
        {"t.pvti",
         "<VTKFile><PImageData WholeExtent=\"0 1 0 1 0 1\"><PPointData>"
         "<PDataArray Name=\"T\"/></PPointData><Piece Extent=\"0 2 0 1 0 1\" "
         "Source=\"a.vti\"/></PImageData></VTKFile>"},
        {"u.pvti",
         "<VTKFile><PImageData WholeExtent=\"0 1 0 1 0 1\" Spacing=\"1 0 1\">"
         "<PPointData><PDataArray Name=\"T\"/></PPointData><Piece "
         "Extent=\"0 1 0 1 0 1\" Source=\"a.vti\"/></PImageData></VTKFile>"},
        {"v.pvti",
         "<VTKFile><PImageData WholeExtent=\"0 1 0 1 0 1\"><Piece "
         "Extent=\"0 1 0 1 0 1\" Source=\"a.vti\"/></PImageData></VTKFile>"},
        {"w.pvti",
         "<VTKFile><PImageData WholeExtent=\"0 3 0 1 0 1\"><PPointData>"
         "<PDataArray Name=\"T\"/></PPointData><Piece Extent=\"0 1 0 1 0 1\" "
         "Source=\"a.vti\"/></PImageData></VTKFile>"},
        {"x.pvti",
         "<VTKFile><PImageData WholeExtent=\"0 1 0 1 0 1\"><PPointData>"
         "<PDataArray Name=\"T\"/></PPointData><Piece Extent=\"0 1 0 1 0 1\" "
         "Source=\"nowhere.vti\"/></PImageData></VTKFile>"}}) {
    const std::string path = tempFile(name, text);
    try {
      loadScene(path);
      ADD_FAILURE() << name << " was read";
    } catch (const InputError& e) {
      // (A .pvtu's missing piece is named by the piece's file.)
      const std::string named = name == "n.pvtu"   ? "nowhere.vtu"
                                : name == "x.pvti" ? "nowhere.vti"
                                                   : path;
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
    fs::remove(path);
  }
}

// Points: a unit cube (0-7, VTK's hexahedron order), a wedge on top
// (4, 5, 8 / 7, 6, 9), a pyramid below (0-3, apex 10).
constexpr const char* kThreeCellPoints =
    "0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1  0.5 0 2  0.5 1 2  0.5 0.5 -1";

// A .vtu named `name` of those points as a hexahedron, a wedge, a pyramid
// and a line, with `data` (its PointData and CellData elements).
std::string threeCellsAndALine(const std::string& name, const std::string& data) {
  return tempFile(name, fmt::format(R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="11" NumberOfCells="4">
      {}
      <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">{}</DataArray></Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 4 5 6 7  4 5 8 7 6 9  0 1 2 3 10  0 6</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">8 14 19 21</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">12 13 14 3</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
)",
                                    data, kThreeCellPoints));
}

// An unstructured grid of a hexahedron, a wedge, a pyramid and a line: the
// solids cut into tetrahedra that fill them, the line left out; the values
// normalised; read from XML (.vtu) and legacy (.vtk) files alike.
TEST(VtkFile, UnstructuredGridsBecomeTetrahedra) {
  const std::string points = kThreeCellPoints;
  const std::string values = "0 1 2 3 4 5 6 7 8 9 10";
  const std::string vtu = threeCellsAndALine(
      "h.vtu", R"(<PointData Scalars="T"><DataArray type="Float32" Name="T" format="ascii">)" +
                   values + "</DataArray></PointData>");
  const std::string vtk = tempFile("h.vtk", fmt::format(R"(# vtk DataFile Version 3.0
three cells and a line
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 11 float
{}
CELLS 4 25
8 0 1 2 3 4 5 6 7
6 4 5 8 7 6 9
5 0 1 2 3 10
2 0 6
CELL_TYPES 4
12
13
14
3
POINT_DATA 11
SCALARS T float 1
LOOKUP_TABLE default
{}
)",
                                                        points, values));
  for (const std::string& path : {vtu, vtk}) {
    const Scene scene = loadScene(path);
    const UnstructuredVolume* v = nullptr;
    for (const Geometry& g : scene.geometries)
      if (auto* u = dynamic_cast<const UnstructuredVolume*>(g.shape.get())) v = u;
    ASSERT_NE(v, nullptr) << path;
    EXPECT_EQ(v->cellCount(), 6u + 3u + 2u) << path;
    // Every point of the three solids lies in a cell; the value is linear there.
    float sum = 0;
    int found = 0;
    for (const Vec3f p :
         {Vec3f(0.3f, 0.6f, 0.4f), Vec3f(0.5f, 0.5f, 1.5f), Vec3f(0.5f, 0.4f, -0.5f)}) {
      for (uint32_t c = 0; c < v->primitiveCount(); ++c) {
        float value;
        if (v->valueAt(c, p, value)) {
          ++found;
          sum += value;
          EXPECT_GE(value, 0.0f);
          EXPECT_LE(value, 1.0f);
          break;
        }
      }
    }
    EXPECT_EQ(found, 3) << path;
    EXPECT_NE(scene.geometries.back().name.find("1 cells that are not solids left out"),
              std::string::npos)
        << scene.geometries.back().name;
    LoadOptions missing;
    missing.field = "pressure";
    try {
      loadScene(path, missing);
      ADD_FAILURE() << "an array that is not there was taken";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("point arrays: T"), std::string::npos) << e.what();
    }
    fs::remove(path);
  }
}

// A curvilinear grid (.vts): its hexahedra, here two stacked and sheared,
// with the point array linear in each tetrahedron.
TEST(VtkFile, StructuredGridsAreHexahedra) {
  const std::string vts = tempFile("s.vts", R"(<?xml version="1.0"?>
<VTKFile type="StructuredGrid" version="0.1" byte_order="LittleEndian">
  <StructuredGrid WholeExtent="0 1 0 1 0 2">
    <Piece Extent="0 1 0 1 0 2">
      <PointData Scalars="h"><DataArray type="Float32" Name="h" format="ascii">0 0 0 0 1 1 1 1 2 2 2 2</DataArray></PointData>
      <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">
        0 0 0  1 0 0  0 1 0  1 1 0  0.5 0 1  1.5 0 1  0.5 1 1  1.5 1 1  1 0 2  2 0 2  1 1 2  2 1 2
      </DataArray></Points>
    </Piece>
  </StructuredGrid>
</VTKFile>
)");
  const Scene scene = loadScene(vts);
  const UnstructuredVolume* v = nullptr;
  for (const Geometry& g : scene.geometries)
    if (auto* u = dynamic_cast<const UnstructuredVolume*>(g.shape.get())) v = u;
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->cellCount(), 12u);
  // h is z / 2 here (normalised over [0, 2]); sheared x follows z / 2.
  for (const Vec3f p : {Vec3f(0.5f, 0.5f, 0.5f), Vec3f(1.2f, 0.3f, 1.5f)}) {
    bool found = false;
    for (uint32_t c = 0; c < v->primitiveCount() && !found; ++c) {
      float value;
      if (v->valueAt(c, p, value)) {
        found = true;
        EXPECT_NEAR(value, p.z / 2, 1e-5f);
      }
    }
    EXPECT_TRUE(found) << p.z;
  }
  fs::remove(vts);
}

// A cell array is constant over each cell (its points duplicated per cell),
// chosen by name beside a point array, or taken when there is no point array.
TEST(VtkFile, UnstructuredCellArraysAreConstantOverEachCell) {
  for (const bool withPointArray : {true, false}) {
    const std::string pointData =
        withPointArray ? R"(<PointData><DataArray type="Float32" Name="T" format="ascii">)"
                         "0 1 2 3 4 5 6 7 8 9 10</DataArray></PointData>"
                       : "";
    const std::string vtu = threeCellsAndALine(
        "c.vtu", pointData + R"(<CellData><DataArray type="Float32" Name="P" format="ascii">)"
                             "10 20 30 40</DataArray></CellData>");
    LoadOptions options;
    if (withPointArray) options.field = "P";
    const Scene scene = loadScene(vtu, options);
    const UnstructuredVolume* v = nullptr;
    for (const Geometry& g : scene.geometries)
      if (auto* u = dynamic_cast<const UnstructuredVolume*>(g.shape.get())) v = u;
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(v->cellCount(), 11u);
    EXPECT_NE(scene.geometries.back().name.find("cells 'P' [10, 40]"), std::string::npos)
        << scene.geometries.back().name;
    // The hexahedron's value (10) everywhere in it, the wedge's (20) and the
    // pyramid's (30), normalised over [10, 40].
    const std::pair<Vec3f, float> expected[] = {{Vec3f(0.3f, 0.6f, 0.4f), 0.0f},
                                                {Vec3f(0.9f, 0.2f, 0.1f), 0.0f},
                                                {Vec3f(0.5f, 0.5f, 1.5f), 1 / 3.0f},
                                                {Vec3f(0.5f, 0.4f, -0.5f), 2 / 3.0f}};
    for (const auto& [p, want] : expected) {
      bool found = false;
      for (uint32_t c = 0; c < v->primitiveCount() && !found; ++c) {
        float value;
        if (v->valueAt(c, p, value)) {
          found = true;
          EXPECT_NEAR(value, want, 1e-6f) << p.x << " " << p.y << " " << p.z;
        }
      }
      EXPECT_TRUE(found);
    }
    fs::remove(vtu);
  }
}

}  // namespace
}  // namespace ferry
