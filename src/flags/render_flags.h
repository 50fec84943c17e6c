// The flags of `ferry render` that say what to render and how: their names,
// help, defaults and checks, and the SessionSettings they make. `ferry view`
// shares them, and the library takes them by name (ferry::api::Options::
// settings), so the command line and the library are one set of settings.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "flags/camera_flags.h"
#include "flags/partition_flags.h"

namespace CLI {
class App;
}

namespace ferry {

class Communicator;
struct SessionSettings;

struct RenderOptions {
  std::string scene = "builtin:island";
  std::string size = "1280x720";
  std::string crop;  // --crop x0,x1,y0,y1 (fractions); empty: the whole image
  int samplesPerPixel = 1;
  int frames = 1;
  int maxDepth = 5;
  std::string view;
  uint32_t seed = 1;
  int threads = 0;
  std::string output = "ferry.png";
  std::string statsPath;
  float exposure = 0;
  // --max-sample-luminance: NaN: the scene's own clamp (pbrt's Film); 0: none.
  float maxSampleLuminance = std::nanf("");
  bool quiet = false;
  // --env-fallback: a missing environment map becomes a constant light.
  bool envFallback = false;
  // --field: the array a VTK file is rendered by (LoadOptions::field).
  std::string field;
  // Whether --size / -o were given; if not, a scene's own (pbrt's Film) apply.
  bool sizeGiven = false;
  bool maxDepthGiven = false;  // else the scene's Integrator maxdepth, if it has one
  bool outputGiven = false;
  std::string forwarding = "proxies";
  std::string exchange = "auto";
  std::string checkpoint, resume;
  // --aov: first-surface features beside the colour, as a comma list of
  // render/aov.h's names (empty: none).
  std::string aov;
  int checkpointEvery = 10;
  double timeLimit = 0;
  uint32_t chunkPixels = 8192;
  // --path-layout: auto (Path8 up to 8 ranks, Path64 up to 64, replay above),
  // mask (Path8/Path64; at most 64 ranks) or replay (at any rank count).
  std::string pathLayout = "auto";
  // --retrace: "remote" re-traces only paths whose hit another rank found;
  // "all" re-traces every shaded path (the paper). Same image.
  std::string retrace = "remote";
  // --mis: "on" weighs light and BSDF samples (multiple importance
  // sampling); "off" counts emitters only through light samples.
  std::string mis = "on";
  std::string misHeuristic = "power";   // --mis-heuristic: power or balance
  std::string lightChoice = "near";     // --light-choice: near or power
  std::string lightPaths = "auto";      // --light-paths: auto, on or off
  std::string transmittance = "ratio";  // --transmittance: ratio or delta
  std::string subsurface = "probe";     // --subsurface: probe or walk
  std::string sampler = "sobol";        // --sampler: sobol or independent
  // --volume-opacity, --color-map: transfer-function volumes restyled.
  float volumeOpacity = 1;
  std::string colorMap;
  // --volume-bricks: auto (large grids bricked, shapes/volume_brick.h), 0
  // (every rank holds every volume whole) or N (bricks of N voxels a side).
  std::string volumeBricks = "auto";
  // --data-groups G: the ranks split into G groups that each hold the whole
  // scene and render every G-th sample.
  int dataGroups = 1;
  // --instancing: "shared" gives an Embree instance level only to objects a
  // rank places more than once or transformed; "always" to every object.
  std::string instancing = "shared";
  // --partitioner (alias --partition) and the partitioners' flags: made on
  // the fly (every rank runs the same deterministic partitioner); ignored
  // when the scene is a part directory (ferry partition -o DIR). No
  // partitioner given: best on more than one rank.
  PartitionFlags partition;
  // --show-partition[=N]: draw the partition instead of rendering (0: off;
  // -1: for as many ranks as MPI runs; N: for N ranks).
  int showPartition = 0;
  // --look-from/--look-at/--up/--fov: a camera given outright.
  CameraFlags camera;
  // The flags given on the command line, by long name without dashes, as
  // text (`ferry render` hands them to the library as Options::settings).
  std::map<std::string, std::string> given;
  // `ferry view` and the library share these options but write no image file.
  bool writesImage = true;
};

// The options `render` and `view` share: the scene, how it is rendered and
// spread over ranks (not the output, frames or checkpoints).
void addRenderingOptions(CLI::App* command, RenderOptions& options);
// --checkpoint, --checkpoint-every, --resume and --time-limit: how a render
// that runs for long is kept and continued; --aov: what it writes beside the
// colour (render's, and the library's; the viewer shows no AOVs).
void addRunOptions(CLI::App* command, RenderOptions& options);
// The flags, checked, as a session's settings: every mode parsed once.
SessionSettings sessionSettings(const RenderOptions& options, const Communicator& comm);

// "1280x720" -> (1280, 720); throws InputError naming the flag.
void parseImageSize(const std::string& text, int& width, int& height);
// A --volume-bricks value (render, view, partition, info): "auto"
// (kAutoBricks), 0 (whole) or a brick size in voxels; InputError otherwise.
int parseVolumeBricks(const std::string& value);
// --partitioner, --keep-objects-whole and --replication-budget (and the
// seed, which the random partitioner uses) into `settings`; throws InputError.
void applyPartitionerFlags(const RenderOptions& options, SessionSettings& settings);

}  // namespace ferry
