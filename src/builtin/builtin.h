// Built-in procedural scenes, named "builtin:NAME?key=value&...".
// Each is deterministic from its seed and has a scale knob. A built-in can be
// described (counts and memory estimate) without generating its geometry, so
// `ferry info` answers instantly even at scales of 1e10 instanced triangles.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "scene/mesh_store.h"
#include "scene/scene.h"
#include "scene/scene_summary.h"

namespace ferry {

struct BuiltinParams {
  std::string
      name;  // "island", "landscape", "cornell", "furnace", "volume", "fur", "particles", "tets"
  double scale = 1.0;  // grows the scene; meaning per built-in (see its header)
  uint32_t seed = 1;
  std::optional<int> size;          // builtin:volume: samples a side
  std::optional<uint64_t> strands;  // builtin:fur: hair strands
  std::optional<uint64_t> count;    // builtin:particles: spheres; builtin:tets: tetrahedra
};

bool isBuiltinSpec(const std::string& spec);  // starts with "builtin:"
// Parses "builtin:island?scale=4&seed=7"; throws InputError on an unknown
// name or key, or a bad value, listing what is accepted.
BuiltinParams parseBuiltinSpec(const std::string& spec);
std::vector<std::string> builtinNames();

// With `store`, meshes are kept in it, not in memory (scene/mesh_store.h).
Scene generateBuiltin(const BuiltinParams& params, std::shared_ptr<MeshStore> store = nullptr);
SceneSummary describeBuiltin(const BuiltinParams& params);

}  // namespace ferry
