// PLY meshes (Stanford polygon files): the standalone reader behind `.ply`
// scenes and pbrt's `plymesh` shape.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/byte_stream.h"
#include "io/load_options.h"
#include "scene/scene.h"

namespace ferry {

// Reads `path` into a mesh (positions, and normals and uvs when the file has
// them; material 0): ascii or binary PLY 1.0, any scalar type, faces as
// triangles or fans, tristrips too. Throws InputError naming the file and, in
// the header or an ASCII body, the line; in a binary body the element and its
// byte offset. The header's counts are checked against the file's size
// before anything is allocated. Streams through a 64 KiB buffer (the file is
// never held in memory); reports progress through `options` for large files.
// What is read and checked: docs/formats.md, "PLY".
Mesh readPly(const std::string& path, const LoadOptions& options = {});

// What a PLY file holds: a mesh, or particles (a vertex-only file whose
// vertices have a "radius" property: the positions and the radii).
struct PlyContents {
  Mesh mesh;
  std::vector<float> radii;  // particles only
};
PlyContents readPlyContents(ByteStream& stream, const LoadOptions& options = {});
// The same from any stream (a fuzzer's bytes); `stream.size()` bounds the counts.
Mesh readPly(ByteStream& stream, const LoadOptions& options = {});

// A `.ply` file as a scene: its mesh (or its particles, as spheres) as one
// object with one instance, a grey diffuse material, and the default view
// and lights that OBJ files get.
Scene loadPlyScene(const std::string& path, const LoadOptions& options = {});

}  // namespace ferry
