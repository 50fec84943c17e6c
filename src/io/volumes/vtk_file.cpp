// VTK files (.vti image data, .vtp points) through the XML readers of
// Debian's VTK: the only file that includes VTK's headers.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMatrix3x3.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStructuredGrid.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridReader.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLStructuredGridReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.h"
#include "io/default_lighting.h"
#include "io/volumes/volume_files.h"
#include "media/medium.h"
#include "shapes/spheres.h"
#include "shapes/unstructured_volume.h"
#include "shapes/volume_brick.h"

namespace ferry {
namespace {

// VTK reports a reader's errors as events, not exceptions: the first kept.
class ErrorCatcher final : public vtkCommand {
 public:
  static ErrorCatcher* New() { return new ErrorCatcher; }
  void Execute(vtkObject*, unsigned long, void* data) override {
    if (message.empty() && data) message = static_cast<const char*>(data);
  }
  std::string message;
};

// Reads `path` with `Reader` (a vtkXML*Reader); InputError naming the file if VTK fails.
template <typename Reader>
vtkSmartPointer<Reader> readVtk(const std::string& path, const char* what) {
  if (!std::filesystem::is_regular_file(path))
    throw InputError(fmt::format("{}: no such file", path));
  auto reader = vtkSmartPointer<Reader>::New();
  vtkNew<ErrorCatcher> errors;
  reader->AddObserver(vtkCommand::ErrorEvent, errors);
  reader->SetFileName(path.c_str());
  if constexpr (std::is_same_v<Reader, vtkUnstructuredGridReader>) {
    if (!reader->IsFileUnstructuredGrid())
      throw InputError(fmt::format("{}: not a legacy VTK {} file", path, what));
  } else if (!reader->CanReadFile(path.c_str())) {
    throw InputError(fmt::format("{}: not a VTK XML {} file", path, what));
  }
  // VTK's parser and pipeline print their own errors: the reader's is ours to say.
  const bool display = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  reader->Update();
  vtkObject::SetGlobalWarningDisplay(display);
  if (!errors->message.empty() || reader->GetErrorCode() != 0 || !reader->GetOutput()) {
    std::string message = errors->message;
    while (!message.empty() && (message.back() == '\n' || message.back() == ' '))
      message.pop_back();
    throw InputError(
        fmt::format("{}: VTK cannot read it ({})", path, message.empty() ? "no detail" : message));
  }
  return reader;
}

// The names of a point or cell data's arrays, for messages.
std::string arrayNames(vtkFieldData* data) {
  std::vector<std::string> names;
  for (int i = 0; data && i < data->GetNumberOfArrays(); ++i)
    names.push_back(data->GetArrayName(i) ? data->GetArrayName(i) : "(unnamed)");
  return names.empty() ? "none" : fmt::format("{}", fmt::join(names, ", "));
}

// A tuple's value: itself, or a vector's magnitude.
double tupleValue(vtkDataArray* a, vtkIdType i) {
  const int n = a->GetNumberOfComponents();
  if (n == 1) return a->GetComponent(i, 0);
  double sum = 0;
  for (int c = 0; c < n; ++c) sum += a->GetComponent(i, c) * a->GetComponent(i, c);
  return std::sqrt(sum);
}

// The first `count` values of `array` (vectors by magnitude), their range
// in `lo` and `hi`. InputError naming the file and, by `where(i)`, value i
// if one is NaN or beyond a float.
template <typename Where>
std::vector<float> finiteValues(vtkDataArray* array, uint64_t count, const std::string& path,
                                double& lo, double& hi, Where&& where) {
  std::vector<float> values(count);
  lo = std::numeric_limits<double>::max();
  hi = std::numeric_limits<double>::lowest();
  for (uint64_t i = 0; i < count; ++i) {
    const double v = tupleValue(array, vtkIdType(i));
    if (!std::isfinite(v) || !std::isfinite(float(v)))
      throw InputError(fmt::format("{}: array '{}' {} is {}", path,
                                   array->GetName() ? array->GetName() : "", where(i), v));
    values[i] = float(v);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return values;
}

// Every named point and cell array of `data` with its finite range (vectors
// by magnitude): what could be rendered instead. A cell array named as a
// point array is left out (the name chooses the point array).
std::vector<VolumeField> fieldsOf(vtkDataSet* data) {
  std::vector<VolumeField> out;
  auto add = [&](vtkDataSetAttributes* d, bool atCells) {
    for (int i = 0; d && i < d->GetNumberOfArrays(); ++i) {
      vtkDataArray* a = d->GetArray(i);
      if (!a || !a->GetName() || !*a->GetName()) continue;
      if (atCells && data->GetPointData()->GetArray(a->GetName())) continue;
      VolumeField f{a->GetName(), atCells, a->GetNumberOfComponents(), 0, 0};
      double range[2];
      a->GetFiniteRange(range, f.components > 1 ? -1 : 0);
      if (range[0] <= range[1]) f.lo = range[0], f.hi = range[1];
      out.push_back(std::move(f));
    }
  };
  add(data->GetPointData(), false);
  add(data->GetCellData(), true);
  return out;
}

// The index of `array` among `fields` (-1: not there).
int32_t fieldIndex(const std::vector<VolumeField>& fields, vtkDataArray* array, bool atCells) {
  for (size_t i = 0; i < fields.size(); ++i)
    if (array->GetName() && fields[i].name == array->GetName() && fields[i].atCells == atCells)
      return int32_t(i);
  return -1;
}

// `values` mapped to [0, 1] by the range [lo, hi].
void normalise(std::vector<float>& values, double lo, double hi) {
  const double range = hi - lo;
  for (float& v : values) v = range > 0 ? float((double(v) - lo) / range) : 0.0f;
}

// Values of `array` (vectors by magnitude) normalised to [0, 1] by their range.
template <typename Where>
std::vector<float> normalisedValues(vtkDataArray* array, uint64_t count, const std::string& path,
                                    double& lo, double& hi, Where&& where) {
  std::vector<float> values = finiteValues(array, count, path, lo, hi, std::forward<Where>(where));
  normalise(values, lo, hi);
  return values;
}

}  // namespace

Scene loadVtkImageScene(const std::string& path, const std::string& field) {
  auto reader = readVtk<vtkXMLImageDataReader>(path, "image data (.vti)");
  vtkImageData* image = reader->GetOutput();
  int extent[6];
  image->GetExtent(extent);
  for (int a = 0; a < 3; ++a)
    if (extent[2 * a + 1] < extent[2 * a])
      throw InputError(
          fmt::format("{}: VTK read no image from it (malformed, truncated or empty: extent {})",
                      path, fmt::join(std::vector<int>(extent, extent + 6), " ")));
  if (vtkMatrix3x3* d = image->GetDirectionMatrix(); d && !d->IsIdentity())
    throw InputError(fmt::format("{}: a rotated image (its direction is not the identity)", path));
  // The array: named, or the active point scalars, or the first point array;
  // a cell array when no point array has the name.
  vtkPointData* points = image->GetPointData();
  vtkCellData* cells = image->GetCellData();
  vtkDataArray* array = nullptr;
  bool atCells = false;
  if (!field.empty()) {
    array = points->GetArray(field.c_str());
    if (!array && (array = cells->GetArray(field.c_str()))) atCells = true;
    if (!array)
      throw InputError(fmt::format("{}: no array '{}' (point arrays: {}; cell arrays: {})", path,
                                   field, arrayNames(points), arrayNames(cells)));
  } else {
    array = points->GetScalars() ? points->GetScalars() : points->GetArray(0);
    if (!array && (array = cells->GetScalars() ? cells->GetScalars() : cells->GetArray(0)))
      atCells = true;
    if (!array) throw InputError(fmt::format("{}: no point or cell array to render", path));
  }
  // Samples: at the points (each the centre of a cell `spacing` wide), or at
  // the cells' centres.
  int dims[3];
  double origin[3], spacing[3];
  image->GetOrigin(origin);
  image->GetSpacing(spacing);
  Box3f box;
  uint64_t samples = 1;
  for (int a = 0; a < 3; ++a) {
    const int lo = extent[2 * a], hi = extent[2 * a + 1];
    dims[a] = atCells ? std::max(hi - lo, 1) : hi - lo + 1;
    if (!(spacing[a] > 0) || !std::isfinite(spacing[a]) || !std::isfinite(origin[a]))
      throw InputError(fmt::format("{}: spacing {} along {}: expected a positive number", path,
                                   spacing[a], "xyz"[a]));
    const double first = atCells ? lo : lo - 0.5;
    box.lower[a] = float(origin[a] + first * spacing[a]);
    box.upper[a] = float(origin[a] + (first + dims[a]) * spacing[a]);
    samples *= uint64_t(dims[a]);
  }
  if (uint64_t(array->GetNumberOfTuples()) != samples)
    throw InputError(fmt::format("{}: array '{}' has {} values where the image has {}", path,
                                 array->GetName() ? array->GetName() : "",
                                 array->GetNumberOfTuples(), samples));
  double lo, hi;
  std::vector<float> values = normalisedValues(array, samples, path, lo, hi, [&](uint64_t i) {
    return fmt::format("value {} (x {}, y {}, z {})", i, i % dims[0], (i / dims[0]) % dims[1],
                       i / (uint64_t(dims[0]) * dims[1]));
  });
  TransferFunction tf = TransferFunction::standard();
  tf = tf.withScale(tf.scale() / maxComponent(box.size()));  // as a raw: volume's
  // The name says which array and its range (ferry info lists it).
  const std::string name =
      fmt::format("{} {} '{}' [{:g}, {:g}]{}", std::filesystem::path(path).filename().string(),
                  atCells ? "cells" : "points", array->GetName() ? array->GetName() : "", lo, hi,
                  array->GetNumberOfComponents() > 1 ? " (magnitude)" : "");
  auto grid = std::make_shared<DensityGrid>(dims[0], dims[1], dims[2], std::move(values));
  Scene scene = volumeScene(
      name,
      transferFunctionMedium(name, std::move(grid), std::make_shared<TransferFunction>(tf), box),
      box);
  scene.volumeFields = fieldsOf(image);
  scene.volumeField = fieldIndex(scene.volumeFields, array, atCells);
  return scene;
}

Scene loadVtkParticleScene(const std::string& path, const std::string& field) {
  auto reader = readVtk<vtkXMLPolyDataReader>(path, "poly data (.vtp)");
  vtkPolyData* data = reader->GetOutput();
  vtkPoints* points = data->GetPoints();
  const vtkIdType n = points ? points->GetNumberOfPoints() : 0;
  if (n == 0)
    throw InputError(
        fmt::format("{}: VTK read no points from it (malformed, truncated or empty)", path));
  const std::string name = field.empty() ? "radius" : field;
  vtkDataArray* radius = data->GetPointData()->GetArray(name.c_str());
  if (!radius || radius->GetNumberOfComponents() != 1)
    throw InputError(fmt::format(
        "{}: no point array '{}' of one component to take as the particles' radius (point "
        "arrays: {}; the field setting names another)",
        path, name, arrayNames(data->GetPointData())));
  std::vector<Vec3f> centres(static_cast<size_t>(n));
  std::vector<float> radii(static_cast<size_t>(n));
  for (vtkIdType i = 0; i < n; ++i) {
    double p[3];
    points->GetPoint(i, p);
    centres[size_t(i)] = Vec3f(float(p[0]), float(p[1]), float(p[2]));
    radii[size_t(i)] = float(radius->GetComponent(i, 0));
  }
  Scene scene;
  scene.name = std::filesystem::path(path).stem().string();
  Material grey;
  grey.name = "default";
  const int32_t material = scene.addMaterial(grey);
  try {
    scene.addSingleInstanceGeometry(
        {scene.name, material, std::make_shared<Spheres>(std::move(centres), std::move(radii))});
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", path, e.what()));
  }
  addDefaultViewAndLights(scene);
  return scene;
}

namespace {

// A VTK cell as tetrahedra that tile it (VTK's vertex orders): a hexahedron
// in six along its 0-6 diagonal, a wedge in three, a pyramid in two.
// False for a cell kind that is not a solid.
bool appendTets(int type, const vtkIdType* p, std::vector<UnstructuredVolume::Tet>& out) {
  auto tet = [&](int a, int b, int c, int d) {
    out.push_back({uint32_t(p[a]), uint32_t(p[b]), uint32_t(p[c]), uint32_t(p[d])});
  };
  switch (type) {
    case VTK_TETRA:
      tet(0, 1, 2, 3);
      return true;
    case VTK_HEXAHEDRON:
      tet(0, 1, 2, 6), tet(0, 1, 5, 6), tet(0, 3, 2, 6), tet(0, 3, 7, 6), tet(0, 4, 5, 6),
          tet(0, 4, 7, 6);
      return true;
    case VTK_VOXEL:  // a hexahedron with its points in x, y, z order
      tet(0, 1, 3, 7), tet(0, 1, 5, 7), tet(0, 2, 3, 7), tet(0, 2, 6, 7), tet(0, 4, 5, 7),
          tet(0, 4, 6, 7);
      return true;
    case VTK_WEDGE:
      tet(0, 1, 2, 3), tet(1, 2, 3, 4), tet(2, 3, 4, 5);
      return true;
    case VTK_PYRAMID:
      tet(0, 1, 2, 4), tet(0, 2, 3, 4);
      return true;
    default:
      return false;
  }
}

}  // namespace

namespace {

// An unstructured grid's solid cells as tetrahedra, with the array's values
// per point as read (not yet normalised) and their range.
struct UnstructuredCells {
  std::vector<Vec3f> points;
  std::vector<float> values;
  std::vector<UnstructuredVolume::Tet> tets;
  uint64_t cells = 0, skipped = 0;
  std::string array;  // "points 'NAME'" or "cells 'NAME'", " (magnitude)" for vectors
  double lo = 0, hi = 0;
  Box3f box;
  std::vector<VolumeField> fields;  // every array the grid holds
  int32_t field = -1;               // the one read, among them
};

// The grid in the file at `path` (.vtk legacy, .vts, else .vtu).
struct ReadGrid {
  vtkDataSet* grid = nullptr;
  vtkSmartPointer<vtkObject> reader;
};
ReadGrid readGrid(const std::string& path) {
  // Any of the three as a data set of cells: a structured grid's cells are
  // hexahedra (quadrilaterals or lines where a side is one point thick,
  // which are not solids).
  const std::string extension = std::filesystem::path(path).extension().string();
  ReadGrid out;
  if (extension == ".vtk") {
    auto r = readVtk<vtkUnstructuredGridReader>(path, "unstructured grid (.vtk)");
    out.grid = r->GetOutput();
    out.reader = r;
  } else if (extension == ".vts") {
    auto r = readVtk<vtkXMLStructuredGridReader>(path, "structured grid (.vts)");
    out.grid = r->GetOutput();
    out.reader = r;
  } else {
    auto r = readVtk<vtkXMLUnstructuredGridReader>(path, "unstructured grid (.vtu)");
    out.grid = r->GetOutput();
    out.reader = r;
  }
  return out;
}

UnstructuredCells readCells(const std::string& path, const std::string& field) {
  const ReadGrid read = readGrid(path);
  vtkDataSet* grid = read.grid;
  const vtkIdType n = grid->GetNumberOfPoints();
  if (n == 0 || grid->GetNumberOfCells() == 0)
    throw InputError(
        fmt::format("{}: VTK read no cells from it (malformed, truncated or empty)", path));
  // The array: a point array by name, else a cell array by name; without a
  // name the active point scalars, the first point array, else the same of
  // the cells. A cell array is constant over each cell: every cell gets
  // points of its own carrying its value (so those points are not shared).
  vtkPointData* pointData = grid->GetPointData();
  vtkCellData* cellData = grid->GetCellData();
  auto firstOf = [](vtkDataSetAttributes* d) {
    return d->GetScalars() ? d->GetScalars() : d->GetArray(0);
  };
  vtkDataArray* array = field.empty() ? firstOf(pointData) : pointData->GetArray(field.c_str());
  bool atCells = false;
  if (!array && (array = field.empty() ? firstOf(cellData) : cellData->GetArray(field.c_str())))
    atCells = true;
  if (!array)
    throw InputError(
        fmt::format("{}: no point or cell array{} to render (point arrays: {}; cell "
                    "arrays: {})",
                    path, field.empty() ? "" : " '" + field + "'", arrayNames(pointData),
                    arrayNames(cellData)));
  UnstructuredCells out;
  out.fields = fieldsOf(grid);
  out.field = fieldIndex(out.fields, array, atCells);
  out.cells = uint64_t(grid->GetNumberOfCells());
  out.array = fmt::format("{} '{}'{}", atCells ? "cells" : "points",
                          array->GetName() ? array->GetName() : "",
                          array->GetNumberOfComponents() > 1 ? " (magnitude)" : "");
  const vtkIdType cells = grid->GetNumberOfCells();
  const std::vector<float> arrayValues = finiteValues(
      array, uint64_t(atCells ? cells : n), path, out.lo, out.hi,
      [&](uint64_t i) { return fmt::format("at {} {}", atCells ? "cell" : "point", i); });
  auto addPoint = [&](vtkIdType i, float value) {
    double p[3];
    grid->GetPoint(i, p);
    out.points.push_back(Vec3f(float(p[0]), float(p[1]), float(p[2])));
    out.values.push_back(value);
    out.box.extend(out.points.back());
  };
  if (!atCells)
    for (vtkIdType i = 0; i < n; ++i) addPoint(i, arrayValues[size_t(i)]);
  vtkNew<vtkIdList> ids;
  std::vector<vtkIdType> own;
  for (vtkIdType c = 0; c < cells; ++c) {
    grid->GetCellPoints(c, ids);
    const vtkIdType* cellPoints = ids->GetPointer(0);
    const size_t before = out.points.size();
    if (atCells) {
      own.resize(size_t(ids->GetNumberOfIds()));
      for (size_t k = 0; k < own.size(); ++k) {
        own[k] = vtkIdType(out.points.size());
        addPoint(cellPoints[k], arrayValues[size_t(c)]);
      }
      cellPoints = own.data();
    }
    if (!appendTets(grid->GetCellType(c), cellPoints, out.tets)) {
      ++out.skipped;
      if (atCells) {  // a cell that is not a solid keeps no points
        out.points.resize(before);
        out.values.resize(before);
      }
    }
  }
  if (out.tets.empty())
    throw InputError(fmt::format(
        "{}: no solid cells (tetrahedra, hexahedra, voxels, wedges, pyramids) among its {}", path,
        out.cells));
  return out;
}

// The transfer function of a volume framed by `box`: as a raw: volume's.
std::shared_ptr<const TransferFunction> framedTransfer(const std::string& path, const Box3f& box) {
  if (!(maxComponent(box.size()) > 0))
    throw InputError(fmt::format("{}: its points span no volume", path));
  TransferFunction tf = TransferFunction::standard();
  return std::make_shared<const TransferFunction>(
      tf.withScale(tf.scale() / maxComponent(box.size())));
}

// `cells` normalised by [lo, hi] as a volume geometry of `scene`.
void addVolume(Scene& scene, const std::string& path, const std::string& name,
               UnstructuredCells cells, double lo, double hi,
               std::shared_ptr<const TransferFunction> transfer, uint32_t firstSeed) {
  normalise(cells.values, lo, hi);
  std::shared_ptr<UnstructuredVolume> volume;
  try {
    volume = UnstructuredVolume::make(std::move(cells.points), std::move(cells.values),
                                      std::move(cells.tets), std::move(transfer), firstSeed);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", path, e.what()));
  }
  Material none;
  none.name = "volume";
  scene.addSingleInstanceGeometry({name, scene.addMaterial(none), std::move(volume)});
}

}  // namespace

Scene loadVtkUnstructuredScene(const std::string& path, const std::string& field) {
  UnstructuredCells cells = readCells(path, field);
  const std::string name = fmt::format(
      "{} {} [{:g}, {:g}]{}", std::filesystem::path(path).filename().string(), cells.array,
      cells.lo, cells.hi,
      cells.skipped ? fmt::format(", {} cells that are not solids left out", cells.skipped) : "");
  auto transfer = framedTransfer(path, cells.box);
  Scene scene = framedVolumeScene(name, cells.box);
  scene.volumeFields = cells.fields;
  scene.volumeField = cells.field;
  const double lo = cells.lo, hi = cells.hi;
  addVolume(scene, path, name, std::move(cells), lo, hi, std::move(transfer), 0);
  return scene;
}

namespace {

// A .pvtu's pieces and the arrays it declares (ranges unknown: lowest above highest).
struct PvtuManifest {
  std::vector<std::string> pieces;
  std::vector<VolumeField> fields;
};

// A manifest's `element` (PUnstructuredGrid, PImageData), parsed by
// `parser` (which owns it); InputError naming the file, `what` it should be.
vtkXMLDataElement* manifestElement(const std::string& path, vtkXMLDataParser* parser,
                                   const char* element, const char* what) {
  if (!std::filesystem::is_regular_file(path))
    throw InputError(fmt::format("{}: no such file", path));
  vtkNew<ErrorCatcher> errors;
  parser->AddObserver(vtkCommand::ErrorEvent, errors);
  parser->SetFileName(path.c_str());
  const bool display = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  const int parsed = parser->Parse();
  vtkObject::SetGlobalWarningDisplay(display);
  vtkXMLDataElement* root = parser->GetRootElement();
  if (!parsed || !root || !errors->message.empty())
    throw InputError(fmt::format("{}: not an XML file VTK can parse", path));
  vtkXMLDataElement* found = root->FindNestedElementWithName(element);
  if (std::string_view(root->GetName() ? root->GetName() : "") != "VTKFile" || !found)
    throw InputError(fmt::format("{}: not a VTK {} file", path, what));
  return found;
}

// The named arrays a manifest's PPointData or PCellData element declares
// (ranges unknown: lowest above highest).
std::vector<VolumeField> declaredArrays(vtkXMLDataElement* data, bool atCells) {
  std::vector<VolumeField> out;
  for (int k = 0; k < data->GetNumberOfNestedElements(); ++k) {
    vtkXMLDataElement* a = data->GetNestedElement(k);
    const char* name = a->GetAttribute("Name");
    if (std::string_view(a->GetName() ? a->GetName() : "") != "PDataArray" || !name || !*name)
      continue;
    int components = 1;
    a->GetScalarAttribute("NumberOfComponents", components);
    out.push_back({name, atCells, std::max(components, 1), std::numeric_limits<double>::max(),
                   std::numeric_limits<double>::lowest()});
  }
  return out;
}

PvtuManifest readPvtu(const std::string& path) {
  vtkNew<vtkXMLDataParser> parser;
  vtkXMLDataElement* grid =
      manifestElement(path, parser, "PUnstructuredGrid", "parallel unstructured grid (.pvtu)");
  PvtuManifest out;
  std::vector<VolumeField> cellFields;
  const std::filesystem::path directory = std::filesystem::path(path).parent_path();
  for (int i = 0; i < grid->GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement* e = grid->GetNestedElement(i);
    const std::string_view kind = e->GetName() ? e->GetName() : "";
    if (kind == "PPointData" || kind == "PCellData") {
      const bool atCells = kind == "PCellData";
      for (VolumeField& f : declaredArrays(e, atCells))
        (atCells ? cellFields : out.fields).push_back(std::move(f));
      continue;
    }
    if (kind != "Piece") continue;
    const char* source = e->GetAttribute("Source");
    if (!source || !*source)
      throw InputError(fmt::format("{}: piece {} names no Source file", path, out.pieces.size()));
    out.pieces.push_back((directory / source).string());
  }
  if (out.pieces.empty()) throw InputError(fmt::format("{}: lists no pieces", path));
  for (VolumeField& f : cellFields) {  // as fieldsOf: a point array's name chooses the point array
    bool shadowed = false;
    for (const VolumeField& p : out.fields) shadowed |= p.name == f.name;
    if (!shadowed) out.fields.push_back(std::move(f));
  }
  return out;
}

}  // namespace

std::vector<std::string> readPvtuPieces(const std::string& path) {
  return readPvtu(path).pieces;
}

Scene loadVtkPiecesScene(const std::string& path, const std::string& field, int rank, int ranks,
                         const PieceAgreement& agree) {
  std::vector<std::string> pieces;
  std::vector<std::pair<size_t, UnstructuredCells>> mine;
  PieceSummary summary;
  std::string error;
  try {
    PvtuManifest manifest = readPvtu(path);
    pieces = std::move(manifest.pieces);
    summary.fields = std::move(manifest.fields);
    const auto [first, end] = pieceRanks(pieces.size(), ranks, rank);
    for (size_t k = first; k < end; ++k) {
      UnstructuredCells cells = readCells(pieces[k], field);
      for (VolumeField& f : summary.fields)
        for (size_t i = 0; i < cells.fields.size(); ++i) {
          const VolumeField& c = cells.fields[i];
          if (c.name != f.name || c.atCells != f.atCells) continue;
          f.lo = std::min(f.lo, c.lo);
          f.hi = std::max(f.hi, c.hi);
          if (int32_t(i) == cells.field) summary.field = int32_t(&f - summary.fields.data());
        }
      summary.lo = std::min(summary.lo, cells.lo);
      summary.hi = std::max(summary.hi, cells.hi);
      summary.box.extend(cells.box);
      summary.cells += cells.cells;
      summary.skipped += cells.skipped;
      mine.emplace_back(k, std::move(cells));
    }
  } catch (const InputError& e) {
    error = e.what();
  }
  summary = agree(summary, error);  // every rank's, so that all normalise and frame alike
  const std::string name = fmt::format(
      "{} [{:g}, {:g}], {} pieces{}", std::filesystem::path(path).filename().string(), summary.lo,
      summary.hi, pieces.size(),
      summary.skipped ? fmt::format(", {} cells that are not solids left out", summary.skipped)
                      : "");
  auto transfer = framedTransfer(path, summary.box);
  Scene scene = framedVolumeScene(name, summary.box);
  scene.volumeFields = summary.fields;
  for (VolumeField& f : scene.volumeFields)
    if (!(f.lo <= f.hi)) f.lo = f.hi = 0;  // in no piece
  scene.volumeField = summary.field;
  for (auto& [k, cells] : mine)
    addVolume(
        scene, pieces[k],
        fmt::format("{} {}", std::filesystem::path(pieces[k]).filename().string(), cells.array),
        std::move(cells), summary.lo, summary.hi, transfer, uint32_t(k) * 0x9E3779B1u);
  return scene;
}

namespace {

// A .pvti: the whole image's point extent and placement, its point arrays
// (and the one to render), and its pieces' point extents and files.
struct PvtiManifest {
  std::array<int, 6> whole{};
  std::array<double, 3> origin{}, spacing{};
  std::vector<VolumeField> fields;  // point arrays (ranges unknown)
  int32_t field = -1;
  std::vector<std::array<int, 6>> extents;
  std::vector<std::string> pieces;
};

PvtiManifest readPvti(const std::string& path, const std::string& field) {
  vtkNew<vtkXMLDataParser> parser;
  vtkXMLDataElement* image =
      manifestElement(path, parser, "PImageData", "parallel image data (.pvti)");
  PvtiManifest out;
  if (image->GetVectorAttribute("WholeExtent", 6, out.whole.data()) != 6)
    throw InputError(fmt::format("{}: no WholeExtent (six point indices)", path));
  for (int a = 0; a < 3; ++a)
    if (out.whole[2 * a + 1] < out.whole[2 * a])
      throw InputError(fmt::format("{}: WholeExtent {} is empty", path, fmt::join(out.whole, " ")));
  out.spacing = {1, 1, 1};
  image->GetVectorAttribute("Origin", 3, out.origin.data());
  image->GetVectorAttribute("Spacing", 3, out.spacing.data());
  for (int a = 0; a < 3; ++a)
    if (!(out.spacing[a] > 0) || !std::isfinite(out.spacing[a]) || !std::isfinite(out.origin[a]))
      throw InputError(fmt::format("{}: spacing {} along {}: expected a positive number", path,
                                   out.spacing[a], "xyz"[a]));
  if (const char* direction = image->GetAttribute("Direction")) {
    double d[9];
    if (image->GetVectorAttribute("Direction", 9, d) != 9 ||
        !(d[0] == 1 && d[4] == 1 && d[8] == 1 && d[1] == 0 && d[2] == 0 && d[3] == 0 && d[5] == 0 &&
          d[6] == 0 && d[7] == 0))
      throw InputError(fmt::format("{}: a rotated image (its Direction {} is not the identity)",
                                   path, direction));
  }
  std::vector<std::string> cellArrays;
  const char* active = nullptr;
  const std::filesystem::path directory = std::filesystem::path(path).parent_path();
  for (int i = 0; i < image->GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement* e = image->GetNestedElement(i);
    const std::string_view kind = e->GetName() ? e->GetName() : "";
    if (kind == "PPointData") {
      active = e->GetAttribute("Scalars");
      for (VolumeField& f : declaredArrays(e, false)) out.fields.push_back(std::move(f));
    } else if (kind == "PCellData") {
      for (const VolumeField& f : declaredArrays(e, true)) cellArrays.push_back(f.name);
    } else if (kind == "Piece") {
      const char* source = e->GetAttribute("Source");
      std::array<int, 6> extent;
      if (!source || !*source)
        throw InputError(fmt::format("{}: piece {} names no Source file", path, out.pieces.size()));
      if (e->GetVectorAttribute("Extent", 6, extent.data()) != 6)
        throw InputError(fmt::format("{}: piece {} has no Extent", path, out.pieces.size()));
      for (int a = 0; a < 3; ++a)
        if (extent[2 * a] < out.whole[2 * a] || extent[2 * a + 1] > out.whole[2 * a + 1] ||
            extent[2 * a + 1] < extent[2 * a])
          throw InputError(fmt::format("{}: piece {} extent {} is empty or outside the whole {}",
                                       path, out.pieces.size(), fmt::join(extent, " "),
                                       fmt::join(out.whole, " ")));
      out.extents.push_back(extent);
      out.pieces.push_back((directory / source).string());
    }
  }
  if (out.pieces.empty()) throw InputError(fmt::format("{}: lists no pieces", path));
  // The array: named, else the active point scalars, else the first point array.
  const std::string want = !field.empty() ? field : active ? active : "";
  for (size_t i = 0; i < out.fields.size(); ++i)
    if (out.fields[i].name == want) out.field = int32_t(i);
  if (want.empty() && !out.fields.empty()) out.field = 0;
  if (out.field < 0) {
    std::vector<std::string> points;
    for (const VolumeField& f : out.fields) points.push_back(f.name);
    if (std::find(cellArrays.begin(), cellArrays.end(), want) != cellArrays.end())
      throw InputError(fmt::format(
          "{}: '{}' is a cell array; a .pvti is read by its point arrays ({}; ParaView's Cell "
          "Data to Point Data makes one)",
          path, want,
          points.empty() ? std::string("none") : fmt::format("{}", fmt::join(points, ", "))));
    throw InputError(fmt::format(
        "{}: no point array{} to render (point arrays: {})", path,
        want.empty() ? "" : " '" + want + "'",
        points.empty() ? std::string("none") : fmt::format("{}", fmt::join(points, ", "))));
  }
  return out;
}

}  // namespace

Scene loadVtkImagePiecesScene(const std::string& path, const std::string& field, int rank,
                              int ranks, const PieceAgreement& agree) {
  PvtiManifest manifest;
  PieceSummary summary;
  std::array<int, 3> dims{};
  Box3f box;
  // This rank's bricks: the cells each piece covers and their samples with
  // the ghost layer, as read (normalised once the ranks agree on the range).
  struct Piece {
    std::array<int, 3> lo, hi;
    std::vector<float> samples;
  };
  std::vector<Piece> mine;
  std::string error;
  try {
    manifest = readPvti(path, field);
    summary.fields = manifest.fields;
    for (int a = 0; a < 3; ++a) {
      dims[a] = manifest.whole[2 * a + 1] - manifest.whole[2 * a] + 1;
      // As a .vti: each point the centre of a cell `spacing` wide.
      box.lower[a] =
          float(manifest.origin[a] + (manifest.whole[2 * a] - 0.5) * manifest.spacing[a]);
      box.upper[a] =
          float(manifest.origin[a] + (manifest.whole[2 * a] - 0.5 + dims[a]) * manifest.spacing[a]);
    }
    summary.box = box;
    // A piece of points [a, b] (sharing b with the next piece) is the brick
    // of cells [a, b), the last along an axis [a, n): the pieces must tile.
    std::vector<std::array<int, 6>> cells(manifest.pieces.size());
    uint64_t covered = 0;
    for (size_t k = 0; k < cells.size(); ++k) {
      uint64_t count = 1;
      for (int a = 0; a < 3; ++a) {
        const int first = manifest.extents[k][2 * a] - manifest.whole[2 * a];
        const int last = manifest.extents[k][2 * a + 1] - manifest.whole[2 * a];
        cells[k][2 * a] = first;
        cells[k][2 * a + 1] = last == dims[a] - 1 ? dims[a] : last;
        count *= uint64_t(std::max(cells[k][2 * a + 1] - first, 0));
      }
      covered += count;
    }
    for (size_t p = 0; p < cells.size(); ++p)
      for (size_t q = p + 1; q < cells.size(); ++q) {
        bool overlap = true;
        for (int a = 0; a < 3; ++a)
          overlap = overlap && cells[p][2 * a] < cells[q][2 * a + 1] &&
                    cells[q][2 * a] < cells[p][2 * a + 1];
        if (overlap)
          throw InputError(fmt::format(
              "{}: pieces {} and {} overlap by more than their shared boundary points (ghost "
              "levels are not read)",
              path, p, q));
      }
    const uint64_t all = uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]);
    if (covered != all)
      throw InputError(
          fmt::format("{}: the pieces cover {} of the image's {} cells", path, covered, all));
    const auto [first, end] = pieceRanks(manifest.pieces.size(), ranks, rank);
    // The points each brick's lookups read: its cells' and the layer below
    // them, which the previous pieces hold (absolute VTK point indices).
    std::vector<std::array<int, 6>> needs;
    for (size_t k = first; k < end; ++k) {
      Piece piece;
      std::array<int, 6> need;
      uint64_t samples = 1;
      bool empty = false;
      for (int a = 0; a < 3; ++a) {
        piece.lo[a] = cells[k][2 * a];
        piece.hi[a] = cells[k][2 * a + 1];
        empty = empty || piece.lo[a] >= piece.hi[a];
        need[2 * a] = manifest.whole[2 * a] + std::max(piece.lo[a] - 1, 0);
        need[2 * a + 1] = manifest.whole[2 * a] + std::min(piece.hi[a], dims[a] - 1);
        samples *= uint64_t(std::max(need[2 * a + 1] - need[2 * a] + 1, 0));
      }
      if (empty) continue;  // a piece one point thick inside the image: no cells of its own
      piece.samples.assign(samples, std::numeric_limits<float>::quiet_NaN());
      summary.cells += uint64_t(piece.hi[0] - piece.lo[0]) * uint64_t(piece.hi[1] - piece.lo[1]) *
                       uint64_t(piece.hi[2] - piece.lo[2]);
      mine.push_back(std::move(piece));
      needs.push_back(need);
    }
    // Each piece file that holds some of those points, read once.
    const std::string& name = manifest.fields[size_t(manifest.field)].name;
    for (size_t q = 0; q < manifest.pieces.size() && !mine.empty(); ++q) {
      const std::array<int, 6>& has = manifest.extents[q];
      auto overlaps = [&](const std::array<int, 6>& need) {
        for (int a = 0; a < 3; ++a)
          if (has[2 * a] > need[2 * a + 1] || need[2 * a] > has[2 * a + 1]) return false;
        return true;
      };
      if (std::none_of(needs.begin(), needs.end(), overlaps)) continue;
      const std::string& file = manifest.pieces[q];
      auto reader = readVtk<vtkXMLImageDataReader>(file, "image data (.vti)");
      vtkImageData* image = reader->GetOutput();
      int extent[6];
      image->GetExtent(extent);
      if (!std::equal(extent, extent + 6, has.begin()))
        throw InputError(fmt::format("{}: extent {}, where {} says {}", file,
                                     fmt::join(extent, extent + 6, " "), path,
                                     fmt::join(has, " ")));
      vtkDataArray* array = image->GetPointData()->GetArray(name.c_str());
      if (!array)
        throw InputError(fmt::format("{}: no point array '{}' (point arrays: {})", file, name,
                                     arrayNames(image->GetPointData())));
      for (const VolumeField& f : fieldsOf(image))
        for (VolumeField& s : summary.fields)
          if (s.name == f.name && !f.atCells)
            s.lo = std::min(s.lo, f.lo), s.hi = std::max(s.hi, f.hi);
      const int nx = has[1] - has[0] + 1, ny = has[3] - has[2] + 1;
      for (size_t b = 0; b < mine.size(); ++b) {
        const std::array<int, 6>& need = needs[b];
        if (!overlaps(need)) continue;
        const int bx = need[1] - need[0] + 1, by = need[3] - need[2] + 1;
        for (int z = std::max(has[4], need[4]); z <= std::min(has[5], need[5]); ++z)
          for (int y = std::max(has[2], need[2]); y <= std::min(has[3], need[3]); ++y)
            for (int x = std::max(has[0], need[0]); x <= std::min(has[1], need[1]); ++x) {
              const vtkIdType from =
                  vtkIdType(x - has[0]) +
                  vtkIdType(nx) * (vtkIdType(y - has[2]) + vtkIdType(ny) * vtkIdType(z - has[4]));
              const double v = tupleValue(array, from);
              if (!std::isfinite(v) || !std::isfinite(float(v)))
                throw InputError(fmt::format("{}: array '{}' at point ({}, {}, {}) is {}", file,
                                             name, x, y, z, v));
              mine[b]
                  .samples[size_t(x - need[0]) +
                           size_t(bx) * (size_t(y - need[2]) + size_t(by) * size_t(z - need[4]))] =
                  float(v);
              summary.lo = std::min(summary.lo, v);
              summary.hi = std::max(summary.hi, v);
            }
      }
    }
    if (!mine.empty()) summary.field = manifest.field;
  } catch (const InputError& e) {
    error = e.what();
  }
  summary = agree(summary, error);  // every rank's, so that all normalise alike
  const VolumeField& chosen = summary.fields[size_t(manifest.field)];
  const std::string name =
      fmt::format("{} points '{}' [{:g}, {:g}]{}, {} pieces",
                  std::filesystem::path(path).filename().string(), chosen.name, summary.lo,
                  summary.hi, chosen.components > 1 ? " (magnitude)" : "", manifest.pieces.size());
  auto volume = std::make_shared<VolumeBrick::Volume>();
  volume->dims = dims;
  volume->gridFromWorld = unitFromBox(box);  // as a .vti's medium
  volume->transfer = framedTransfer(path, box);
  Scene scene = framedVolumeScene(name, box);
  scene.volumeFields = summary.fields;
  for (VolumeField& f : scene.volumeFields)
    if (!(f.lo <= f.hi)) f.lo = f.hi = 0;
  scene.volumeField = manifest.field;
  Material none;
  none.name = "volume";
  const int32_t material = scene.addMaterial(none);
  for (Piece& piece : mine) {
    normalise(piece.samples, summary.lo, summary.hi);  // as a .vti's values
    auto brick = std::make_shared<VolumeBrick>(volume, piece.lo, piece.hi,
                                               SharedArray<float>(std::move(piece.samples)));
    if (!(brick->majorant() > 0)) continue;  // it never collides: nothing to hold
    scene.addSingleInstanceGeometry(
        {fmt::format("{} brick {},{},{}", name, piece.lo[0], piece.lo[1], piece.lo[2]), material,
         std::move(brick)});
  }
  return scene;
}

std::pair<size_t, size_t> pieceRanks(size_t pieces, int ranks, int rank) {
  return {pieces * size_t(rank) / size_t(ranks), pieces * size_t(rank + 1) / size_t(ranks)};
}

}  // namespace ferry
