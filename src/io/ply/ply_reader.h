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
// them; material 0). Throws InputError naming the file and, in the header or
// an ASCII body, the line; in a binary body the element and its byte offset.
//
// Formats: ascii, binary_little_endian and binary_big_endian 1.0; every PLY
// scalar type (char/int8 ... double/float64) for every property.
// Vertex properties used: x y z (required), nx ny nz (all three or none), and
// the first complete pair of u v, s t, texture_u texture_v, texture_s
// texture_t. Every other property and element (confidence, intensity,
// colours, edges, materials, lists in vertices) is read past and ignored.
// Faces: the list `vertex_indices` (or `vertex_index`) of element `face`;
// triangles as they are, larger polygons (quads) as triangle fans. Element
// `tristrips` (strips separated by -1) is read too.
//
// Nothing is allocated from the header's word alone: before the body is read
// the counts are checked against the bytes that follow the header (binary:
// each element's smallest encoding; ASCII: two bytes per value), so a lying
// header fails at once with its line instead of allocating gigabytes.
// Errors: a missing or malformed header line, unknown types, a truncated body,
// a face with fewer than 3 vertices, an index out of range, a non-finite
// position, normal or uv, more than 2^31 - 1 vertices or triangles.
//
// Streams through a 64 KiB buffer: the file is never held in memory, only the
// mesh being built. Reports progress through `options` for large files.
Mesh readPly(const std::string& path, const LoadOptions& options = {});
// The same from any stream (a fuzzer's bytes); `stream.size()` bounds the counts.
Mesh readPly(ByteStream& stream, const LoadOptions& options = {});

// A `.ply` file as a scene: its mesh as one object with one instance, a grey
// diffuse material, and the default view and lights that OBJ files get.
Scene loadPlyScene(const std::string& path, const LoadOptions& options = {});

}  // namespace ferry
