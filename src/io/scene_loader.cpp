#include "io/scene_loader.h"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "builtin/builtin.h"
#include "core/error.h"
#include "io/gltf/gltf_loader.h"
#include "io/obj/obj_loader.h"
#include "io/pbrt/pbrt_parser.h"
#include "io/ply/ply_reader.h"
#include "io/volumes/volume_files.h"
#include "scene/mesh_store.h"

namespace ferry {
namespace {

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

Scene loadScene(const std::string& spec, const LoadOptions& options) {
  if (isBuiltinSpec(spec)) {
    Scene scene = generateBuiltin(parseBuiltinSpec(spec), options.meshStore);
    scene.reserveVertexSlack();  // so the trace backend shares every vertex array
    return scene;
  }
  if (isRawVolumeSpec(spec)) return loadRawVolume(spec);
  if (isBrickManifestSpec(spec)) return loadBrickPiece(spec, -1, 1);  // the whole, assembled
  if (!std::filesystem::exists(spec)) throw InputError(fmt::format("{}: no such file", spec));
  std::string ext = lowerExtension(spec);
  Scene scene;
  if (ext == ".obj") {
    scene = loadObj(spec);
  } else if (ext == ".ply") {
    scene = loadPlyScene(spec, options);
  } else if (ext == ".pbrt") {
    scene = loadPbrt(spec, options);
  } else if (ext == ".gltf" || ext == ".glb") {
    scene = loadGltf(spec, options);
  } else if (ext == ".vdb") {
    scene = loadVdbScene(spec);
  } else if (ext == ".nvdb") {
    scene = loadNanoVdbScene(spec);
  } else if (ext == ".vti") {
    scene = loadVtkImageScene(spec, options.field);
  } else if (ext == ".vtp") {
    scene = loadVtkParticleScene(spec, options.field);
  } else if (ext == ".vtu" || ext == ".vtk" || ext == ".vts") {
    scene = loadVtkUnstructuredScene(spec, options.field);
  } else if (ext == ".pvtu" || ext == ".pvti") {  // every piece (many ranks: each its own)
    const PieceAgreement alone = [](const PieceSummary& mine, const std::string& error) {
      if (!error.empty()) throw InputError(error);
      return mine;
    };
    scene = ext == ".pvtu" ? loadVtkPiecesScene(spec, options.field, 0, 1, alone)
                           : loadVtkImagePiecesScene(spec, options.field, 0, 1, alone);
  } else {
    throw InputError(
        fmt::format("{}: unsupported scene format '{}' (supported: .obj, .ply, .pbrt, .gltf, .glb, "
                    ".vdb, .nvdb, .vti, .pvti, .vtp, .vtu, .pvtu, .vtk, .vts, "
                    "raw:PATH?dims=X,Y,Z&format=F, builtin:NAME)",
                    spec, ext));
  }
  scene.validate();
  scene.reserveVertexSlack();  // so the trace backend shares every vertex array
  if (options.meshStore) {     // loaded whole (pbrt stored its meshes as it went)
    for (Mesh& mesh : scene.meshes) options.meshStore->store(mesh);
    scene.meshStore = options.meshStore;
  }
  return scene;
}

SceneSummary describeScene(const std::string& spec, const LoadOptions& options) {
  if (isBuiltinSpec(spec)) return describeBuiltin(parseBuiltinSpec(spec));
  return summarize(loadScene(spec, options));
}

}  // namespace ferry
