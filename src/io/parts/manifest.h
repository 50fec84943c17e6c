// The manifest of a part directory (`ferry partition -o DIR`): manifest.json,
// written last, so a directory with a manifest is complete. It names the
// scene and partitioner, the rank count, and every file with its size and
// payload hash (part_file.h), so a rank can tell a stale or foreign file from
// its own. Its "version" is the part format's: a manifest of a format this
// Ferry does not read (kOldestPartFormatVersion .. kPartFormatVersion) is
// refused with a message saying so.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/scene_summary.h"

namespace ferry {

constexpr const char* kManifestName = "manifest.json";
constexpr const char* kManifestFormat = "ferry-parts";

struct ManifestFile {
  std::string file;  // relative to the directory
  uint64_t bytes = 0;
  uint64_t hash = 0;
};

struct ManifestPart : ManifestFile {
  int rank = 0;
  uint64_t instances = 0;
  uint64_t estimatedBytes = 0;  // memory estimate of what the rank holds
};

struct Manifest {
  uint32_t version = 0;
  std::string scene;        // as given on the command line
  std::string partitioner;  // name
  nlohmann::json options;   // the partitioner's options
  int ranks = 0;
  nlohmann::json summary;  // SceneSummary::toJson() of the scene as given
  uint64_t inputBytes = 0;
  uint64_t replicatedBytes = 0;
  uint64_t proxies = 0;
  double partitionSeconds = 0;
  float filmScale = 1;                           // the scene's Film scale (Scene::filmScale)
  std::optional<std::array<float, 4>> filmCrop;  // Scene::filmCrop
  float filmMaxSampleLuminance = 0, filmMaxComponentValue = 0;  // Scene's, 0: none
  std::string integrator;                                       // Scene::integrator
  std::optional<int> integratorMaxDepth;                        // Scene::integratorMaxDepth
  // Scene's shutter and motion times (motion blur).
  float shutterOpen = 0, shutterClose = 1, motionStart = 0, motionEnd = 1;
  ManifestFile shared;
  std::vector<ManifestPart> parts;
  // `ferry partition --predict-forwards`: ForwardPrediction::toJson() per
  // view (an array; empty when none was asked for).
  nlohmann::json predictions = nlohmann::json::array();

  nlohmann::json toJson() const;
};

// True if `path` is a directory holding a manifest.
bool isPartDirectory(const std::string& path);
// Writes DIR/manifest.json atomically.
void writeManifest(const std::string& directory, const Manifest& manifest);
// Reads and checks DIR/manifest.json; throws InputError naming the file.
Manifest readManifest(const std::string& directory);

// The summary as SceneSummary::toJson() wrote it.
SceneSummary summaryFromJson(const nlohmann::json& j);

}  // namespace ferry
