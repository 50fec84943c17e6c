#include "app/info_command.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>

#include "builtin/builtin.h"
#include "flags/render_flags.h"
#include "io/scene_loader.h"
#include "shapes/volume_brick.h"

namespace ferry {

void addInfoCommand(CLI::App& app, InfoOptions& options) {
  CLI::App* info = app.add_subcommand(
      "info",
      "Print a scene's counts (meshes, triangles, instances, textures, lights, bounds) and its\n"
      "estimated memory by kind. Built-ins are described from their generator's counts without\n"
      "making geometry, so large scales answer at once.");
  info->add_option("scene", options.scene,
                   "Scene file (.obj, .ply, .pbrt, .gltf, .glb) or built-in (builtin:island, "
                   "builtin:landscape, builtin:cornell,\n"
                   "builtin:furnace; parameters as builtin:island?scale=4&seed=7)")
      ->capture_default_str();
  info->add_flag("--json", options.json, "Print JSON instead of a table");
  info->add_flag("--env-fallback", options.envFallback,
                 "Describe a scene whose environment map is missing (as render --env-fallback)");
  info->add_option("--volume-bricks", options.volumeBricks,
                   "Grid volumes counted as render holds them: auto, 0 (whole) or bricks of N\n"
                   "voxels a side (render --volume-bricks)")
      ->capture_default_str();
}

int runInfo(const InfoOptions& options) {
  LoadOptions load;
  load.envFallback = options.envFallback;
  load.progress = [last = -1](uint64_t done, uint64_t total, const std::string& what) mutable {
    int tenth = total ? int(10 * done / total) : 10;
    if (tenth == last) return;
    last = tenth;
    fmt::print(stderr, "load: {}% of {}\n", tenth * 10, what);
  };
  const int bricks = parseVolumeBricks(options.volumeBricks);
  // A built-in is described from its plan, without making it, unless render
  // would brick a grid of it; a file is loaded once, bricked as render would.
  SceneSummary summary;
  bool described = false;
  if (isBuiltinSpec(options.scene)) {
    summary = describeScene(options.scene, load);
    const auto grid = [](const SceneSummary::Medium& m) { return m.kind.rfind("grid", 0) == 0; };
    described = bricks == 0 || std::none_of(summary.media.begin(), summary.media.end(), grid);
  }
  if (!described) {
    Scene scene = loadScene(options.scene, load);
    if (bricks != 0) brickVolumes(scene, bricks);
    summary = summarize(scene);
  }
  if (options.json)
    fmt::print("{}\n", summary.toJson().dump(2));
  else
    fmt::print("{}", summary.toText());
  return 0;
}

}  // namespace ferry
