// Volumes as users have them: OpenVDB files (.vdb, through Debian's
// libopenvdb, which only vdb_file.cpp includes), VTK files (.vti, .vtp,
// .vtu, .vts, .pvtu, legacy .vtk, through Debian's VTK, only in
// vtk_file.cpp) and raw structured grids
// ("raw:PATH?dims=X,Y,Z&format=uint8|uint16|float32", sci-vis style, drawn
// through a transfer function), each loaded as a scene of its own: the grid
// medium in its box, bounded by that box, with a default camera and light
// (as a lone mesh gets them). pbrt's "nanovdb" medium reads .vdb files too.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "media/density_grid.h"
#include "media/transfer_function.h"
#include "media/volume_look.h"
#include "scene/scene.h"

namespace ferry {

// ------------------------------------------------------------------ OpenVDB

// A .vdb file's float grid as a dense density grid: the grid named
// `gridName` ("density" if there is one and no name is given, else the first
// float grid), over the active voxels' bounding box, and the world box it
// covers (each voxel a cell of the grid's voxel size). InputError naming the
// file: unreadable, no float grid, a transform that is not axis-aligned
// scale and translation, a negative or NaN value (naming the voxel), or an
// active box of more than `maxVoxels` (a sparse grid made dense).
struct VdbDensity {
  std::string gridName;
  std::shared_ptr<const DensityGrid> grid;
  Box3f box;  // world (the file's) space
};
constexpr uint64_t kMaxVdbVoxels = uint64_t(1) << 34;  // 64 GiB of floats
VdbDensity readVdbDensity(const std::string& path, const std::string& gridName = "",
                          uint64_t maxVoxels = kMaxVdbVoxels);
// pbrt-v4's nanovdb grids from one read: "density" (required) and
// "temperature" (no grid if the file has none).
std::pair<VdbDensity, VdbDensity> readVdbDensityAndTemperature(const std::string& path,
                                                               uint64_t maxVoxels = kMaxVdbVoxels);

// One grid of a .vdb file to write (writeVdbFile): its name and value type,
// its index-to-world map (a scale per axis, then a rotation about z, then a
// translation), its background and its active voxels. Values are given as
// floats; an integer grid takes each rounded toward zero (0 for NaN, clamped
// to its range).
struct VdbGridToWrite {
  enum class Type : uint8_t { Float, Double, Int32 };
  std::string name;
  Type type = Type::Float;
  std::array<double, 3> scale{1, 1, 1};
  double rotateZDegrees = 0;
  std::array<double, 3> translation{0, 0, 0};
  float background = 0;
  std::vector<std::pair<std::array<int32_t, 3>, float>> voxels;
};
// Writes `grids` to a .vdb file at `path` with OpenVDB (tests and the
// vdbgrids fuzz target build their files so). InputError naming the path if
// OpenVDB refuses a grid (a scale of 0) or the file cannot be written.
void writeVdbFile(const std::string& path, const std::vector<VdbGridToWrite>& grids);

// `ferry render cloud.vdb`: its density as smoke (sigma_a 1, sigma_s 9 per
// unit of density and world length, g 0), framed and lit by default.
Scene loadVdbScene(const std::string& path);

// ------------------------------------------------------------------ NanoVDB

// A .nvdb file's (pbrt-v4's nanovdb medium) float grids "density" (required)
// and "temperature" (none if the file has none), read as readVdbDensity reads
// a .vdb file's, with the same errors naming the file.
std::pair<VdbDensity, VdbDensity> readNanoVdbDensityAndTemperature(
    const std::string& path, uint64_t maxVoxels = kMaxVdbVoxels);
// One float grid to write (tests): dims[0] x dims[1] x dims[2] values, x
// fastest, the first at index `origin`, zeros left inactive.
struct NanoVdbGridToWrite {
  std::string name;
  std::array<int, 3> dims{};
  std::array<int, 3> origin{};
  float voxelSize = 1;
  std::vector<float> values;
};
void writeNanoVdbFile(const std::string& path, const std::vector<NanoVdbGridToWrite>& grids);
// `ferry render cloud.nvdb`: as loadVdbScene.
Scene loadNanoVdbScene(const std::string& path);

// ---------------------------------------------------------------------- VTK

// `ferry render data.vti`: VTK image data (through Debian's VTK) as a volume
// drawn through the standard transfer function, framed as a raw: volume:
// the point array `field` (empty: the active scalars, else the first point
// array; a cell array when no point array has the name or there is none),
// each point the centre of a cell `spacing` wide (cells: their centres), a
// vector by its magnitude, normalised by the array's range. The medium's
// name gives the file, the array and its range. InputError naming the
// file: unreadable, no such array (the arrays listed), a rotated image, a
// NaN (naming the point).
Scene loadVtkImageScene(const std::string& path, const std::string& field = "");
// `ferry render points.vtp`: VTK poly data's points as spheres of the point
// array `field` (empty: "radius") as radius. InputError naming the file: no
// points, no such array (the arrays listed), a radius that is not positive.
Scene loadVtkParticleScene(const std::string& path, const std::string& field = "");

// `ferry render mesh.vtu` (a legacy `mesh.vtk`, a curvilinear `grid.vts`):
// the solid cells as an unstructured volume (shapes/unstructured_volume.h:
// hexahedra, voxels, wedges and pyramids cut into tetrahedra; other cells
// left out, counted in the name) of the array `field` (a point array, else
// a cell array, constant over its cells; empty: the active point scalars,
// else the first point array, else the same of the cells), normalised by
// its range, through the standard transfer function, framed as a raw:
// volume. InputError naming the file: unreadable, no such array (the
// arrays listed), no solid cell, a NaN (naming the point or cell).
Scene loadVtkUnstructuredScene(const std::string& path, const std::string& field = "");
// ParaView's parallel unstructured grid (.pvtu): a manifest of .vtu pieces,
// each a file beside it. The piece files it lists, in order; InputError
// naming the file: unreadable, not a .pvtu, no pieces, a piece without a
// Source.
std::vector<std::string> readPvtuPieces(const std::string& path);
// The pieces [first, second) of `pieces` that rank `rank` of `ranks` reads
// (contiguous runs, as ParaView deals them; none when there are more ranks).
std::pair<size_t, size_t> pieceRanks(size_t pieces, int ranks, int rank);
// What a rank read of a .pvtu: the array's range, the box, the cells (and
// those left out); PieceAgreement combines every rank's (a collective on
// many ranks; the identity on one), or throws InputError on every rank if
// any rank's reading failed (the error given, empty if none).
struct PieceSummary {
  double lo = std::numeric_limits<double>::max();
  double hi = std::numeric_limits<double>::lowest();
  Box3f box;
  uint64_t cells = 0, skipped = 0;
  // The manifest's arrays (the same list on every rank), each with its range
  // over the rank's pieces (lowest above highest: none), and the one read
  // (-1: no piece here).
  std::vector<VolumeField> fields;
  int32_t field = -1;
};
using PieceAgreement = std::function<PieceSummary(const PieceSummary&, const std::string& error)>;
// `ferry render data.pvtu`: rank `rank` of `ranks` reads its pieces only,
// each an unstructured volume of its own (as loadVtkUnstructuredScene
// reads a .vtu) normalised by the range over all pieces and framed by
// their box, so the image is the same on any rank count. A rank with no
// pieces has no geometry. Errors as readPvtuPieces and
// loadVtkUnstructuredScene, naming the piece's file.
Scene loadVtkPiecesScene(const std::string& path, const std::string& field, int rank, int ranks,
                         const PieceAgreement& agree);
// ParaView's parallel image data (.pvti): a manifest of .vti pieces whose
// point extents share their boundary points. Each piece is a brick of the
// cells its points start (shapes/volume_brick.h), the last along an axis
// to the image's end, so the pieces must tile the image (no ghost levels).
// Rank `rank` of `ranks` reads its contiguous run of pieces (as .pvtu)
// through VTK's parallel reader, with the one-sample layer of the next
// pieces its lookups need; the point array `field` (empty: the active
// scalars, else the first), normalised by the range over all pieces, as
// a .vti of the whole would be: the same volume, and with bricks of the
// same cells the same image. InputError naming the file or piece.
Scene loadVtkImagePiecesScene(const std::string& path, const std::string& field, int rank,
                              int ranks, const PieceAgreement& agree);

// --------------------------------------------------------------- raw grids

bool isRawVolumeSpec(const std::string& spec);  // starts with "raw:"

// Bytes a sample of `format` ("uint8", "uint16", "float32") takes; 0 for any other.
size_t rawSampleBytes(const std::string& format);

// "raw:PATH?dims=X,Y,Z&format=uint8|uint16|float32[&spacing=SX,SY,SZ]
// [&origin=OX,OY,OZ][&tf=FILE][&opacity=S]": X*Y*Z samples, x fastest,
// little-endian, each the centre of a cell `spacing` wide (default 1) from
// `origin` (default 0). Values are normalised to [0, 1] (uint8 / 255,
// uint16 / 65535, float32 by the data's own range) and drawn through the
// transfer function in FILE (readTransferFunction; default: the standard
// one), its opacity scale (mean free paths across the box's longest side
// at opacity 1) S when given. InputError naming the file: a
// size that does not match dims and format, dims that are not positive or
// overflow, an unknown format or key, a NaN.
Scene loadRawVolume(const std::string& spec);

// A transfer function file (JSON): {"colors": [[x, r, g, b], ...],
// "opacity": [[x, a], ...], "scale": S} (scale: mean free paths across the
// volume's longest side at opacity 1; optional, default the standard
// one's, 20). InputError naming the file and what is wrong.
TransferFunction readTransferFunction(const std::string& path);

// A scene of `medium` alone in `box` (world space), bounded by it, with a
// default view and lights.
Scene volumeScene(const std::string& name, Medium medium, const Box3f& box);
// That scene without the medium: the view and lights that frame `box`.
Scene framedVolumeScene(const std::string& name, const Box3f& box);

// ------------------------------------------------------ distributed bricks

bool isBrickManifestSpec(const std::string& spec);  // starts with "bricks:"

// "bricks:MANIFEST.json": a volume already spread over the ranks in bricks
// (as a simulation holds it), each rank loading only its own brick files
// (the manifest's format: docs/volumes.md, "Natively distributed bricks").
// A brick file holds its cells [lo, hi) and the ghost layer around them.
// Returns `rank`'s bricks (every brick for rank -1) as VolumeBrick
// geometries restyled by `look`, leaving out those that never collide,
// framed as a volume file is. InputError naming the manifest or the
// brick's file: a malformed manifest, bricks that overlap or leave cells
// uncovered, a file of the wrong size, a NaN, a float32 volume without a
// range.
Scene loadBrickPiece(const std::string& spec, int rank, int ranks, const VolumeLook& look = {});

}  // namespace ferry
