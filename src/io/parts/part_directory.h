// A part directory: what `ferry partition -o DIR` writes and what each rank of
// `ferry render DIR` loads. One part file per rank (part-RRRR.fpart), one
// shared file (shared.fpart: views, film, lights, proxies), and
// manifest.json, written last (an old manifest is removed first, so a
// directory caught half-written has none).
#pragma once

#include <string>

#include "io/parts/manifest.h"
#include "partition/partition.h"
#include "scene/scene.h"

namespace ferry {

// What the manifest records besides the files.
struct PartDirectoryInfo {
  std::string scene;
  std::string partitioner;
  nlohmann::json options = nlohmann::json::object();
  nlohmann::json summary = nlohmann::json::object();
  uint64_t inputBytes = 0;
  uint64_t replicatedBytes = 0;
  double partitionSeconds = 0;
};

// Writes the parts of `scene` (as partitioned: the partition refers to it)
// one after another, straight from the scene. `lights` is lightScene() of the
// scene as given; views and film settings are taken from `scene`.
Manifest writePartDirectory(const std::string& directory, const Scene& scene,
                            const Partition& partition, const Scene& lights,
                            const PartDirectoryInfo& info);

// What one rank renders from: its part (scene with views and film settings
// from the shared file), a partition whose instanceOwners index that part's
// instances and whose proxies are everyone's, and the lights.
struct RankPart {
  Manifest manifest;
  Scene scene;
  Partition partition;
  Scene lights;
};
// Reads the manifest, checks it was made for `ranks` ranks, reads the shared
// file and part `rank`; every failure is an InputError naming the file.
RankPart loadRankPart(const std::string& directory, int rank, int ranks);

// Every part of the directory merged into one scene (content held by several
// ranks appears once per part), with the partition over its instances: for
// pictures and tests, not for rendering.
Scene loadAllParts(const std::string& directory, Partition& partition);

std::string partFileName(int rank);

}  // namespace ferry
