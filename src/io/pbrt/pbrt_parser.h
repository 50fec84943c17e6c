// pbrt scene files (v3 and v4 syntax) to a Ferry Scene: the directives, the
// graphics state, and scene building. Materials and textures are mapped in
// pbrt_materials, spectra in pbrt_spectra, non-triangle shapes in
// shape_tessellation, PLY files in ply_reader.
//
// Instancing stays instancing: every ObjectBegin/ObjectEnd becomes one Ferry
// object, every ObjectInstance one instance. What is not supported is
// skipped with one warning; malformed input is an InputError at
// file:line:column. The directives, shapes, lights and camera read, and the
// approximations: docs/formats.md, "pbrt".
#pragma once

#include <string>
#include <string_view>

#include "io/load_options.h"
#include "scene/scene.h"

namespace ferry {

Scene loadPbrt(const std::string& path, const LoadOptions& options = {});
// The same from text in memory (tests, fuzzers); relative file names resolve
// against `directory`. `name` is used in messages.
Scene loadPbrtFromString(std::string_view text, const std::string& name,
                         const std::string& directory, const LoadOptions& options = {});

}  // namespace ferry
