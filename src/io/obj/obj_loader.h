// Wavefront OBJ with MTL materials and textures, through tinyobjloader.
#pragma once

#include <string>

#include "scene/scene.h"

namespace ferry {

// Loads an OBJ file as single-instance meshes (one per shape and material).
// Throws InputError naming the file and line for malformed input: bad or
// out-of-range indices, NaN or infinite numbers, a truncated file, an unknown
// material, a missing texture.
//
// Two passes over the file, both streaming (the file is never held in memory):
//  1. Validation, line by line, with exact `file:line` messages. tinyobjloader
//     is lenient (bad numbers become 0, bad indices are dropped or crash later)
//     and knows no line numbers, so nothing reaches it unchecked. Errors:
//     - `v` needs 3 to 7 numbers (x y z [w] or x y z r g b), `vt` 1 to 3, `vn` 3;
//       every one a finite decimal number that fits a float.
//     - `f` needs at least 3 vertices, `l` 2, `p` 1, each written v, v/vt,
//       v//vn or v/vt/vn. Index 0 is an error; a positive index must name an
//       element defined *above* the line (no forward references); a negative
//       one counts back from the last element defined above the line.
//     - `usemtl` of a material not defined by an `mtllib` above it; an
//       `mtllib` file that does not exist (relative to the OBJ's directory).
//     - In an MTL: non-numeric or non-finite values; `Kd spectral`/`xyz`,
//       `d -halo`; a map_Kd or map_d whose file is missing (relative to the
//       MTL's directory; backslashes are tried as '/'), reported at the MTL's
//       line, for the materials the OBJ uses (unused materials are not loaded).
//     - A NUL byte (binary data), a line over 16 MiB, a '\' line continuation.
//     - No faces at all: nothing to render.
//     Truncation: a file cut inside a statement ends without a newline, so an
//     error on a final line that has no newline says the file looks truncated.
//     A complete last statement without a newline is fine, and a file cut
//     exactly between two statements cannot be told from a shorter file.
//     Comments (`#` at the start of a line, or a `#` token after the numbers of
//     a statement) are allowed; unknown statements are ignored.
//  2. Building, through tinyobjloader's streaming callback API (its v/vt/vn/f/
//     usemtl/g/o parsing; MTL files through tinyobj::LoadMtl), so the geometry
//     is held once, in the meshes being built.
//
// Meshes: one per (shape, material), where the shape is the latest `o` or `g`
// name (the file stem before any); named "shape/material". Faces are
// triangulated (quads along their shorter diagonal, larger polygons as fans) and
// de-indexed into per-mesh vertices, one per distinct (v, vt, vn). A mesh has
// normals if any of its corners has one; the others get the area-weighted
// normal of their faces. Likewise uvs, (0, 0) where missing.
//
// Materials (only those the faces use; "default" for faces before any usemtl):
//   Kd -> baseColor (1 when there is a map_Kd and no Kd: the texture as it is),
//   map_Kd -> baseColorTexture (multiplied by Kd, as the MTL spec says),
//   Ke -> emission (Ka is never emission), Ns -> roughness = sqrt(2 / (Ns + 2)),
//   Pr -> roughness (wins over Ns), Pm -> metallic, else illum 3/5 -> metallic 1
//   with Ks as the reflectance when Ks is not black, Ni -> ior when Ni >= 1
//   (exporters write 0 or 1 for "unset"; those keep 1.5), d or Tr ->
//   transmission = 1 - d, and illum 4/6/7 with Tf -> transmission = max(Tf),
//   map_d -> alphaTexture (the file's alpha, or its grey level when it has no
//   alpha channel). A texture used by several materials is loaded once;
//   `-clamp on` selects clamped wrapping.
//
// Lights and camera: a view "default" frames the bounds, looking along -z from
// in front (+z), fovY 45. If no material used is emissive, a sun (from above,
// front right) and a constant environment of 0.5 are added so that any OBJ
// renders. If some material is emissive the file is taken to be lit as authored
// (a Cornell box): no sun and a black environment.
Scene loadObj(const std::string& path);

}  // namespace ferry
