// The paper's Figure 4 for any scene: the memory estimate of the largest
// part when the scene is split into 1..N parts, for each of the six
// partitioners, with non-instanced objects broken into their meshes
// (Zellmann et al.) and kept whole. As CSV, and as a plot drawn here.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "partition/partitioner.h"

namespace ferry {

struct Scene;

struct MaxPartSeries {
  std::string partitioner;
  bool whole = false;           // non-instanced content kept as one unit
  std::vector<uint64_t> bytes;  // bytes[n - minRanks]: largest part at n ranks
  double seconds = 0;           // to compute the whole curve
  std::string label() const { return whole ? partitioner + " (whole)" : partitioner; }
};

struct MaxPartReport {
  std::string scene;
  uint64_t inputBytes = 0;  // memory estimate of the scene as given
  int minRanks = 1, maxRanks = 1;
  std::vector<MaxPartSeries> series;
};

// Takes the scene (it is rewritten on the way: broken into meshes, cut for
// `best`; one copy is made for `best` with objects kept whole).
MaxPartReport maxPartReport(Scene scene, const std::string& sceneName, int minRanks, int maxRanks,
                            const PartitionerOptions& base);

// "ranks,<label>,..." then one row per rank count, bytes.
void writeMaxPartCsv(const std::string& path, const MaxPartReport& report);
// Largest part as a percentage of the scene against the rank count (log2
// axis when the range spans 16x or more); solid: broken into meshes, dashed: whole.
std::vector<uint8_t> plotMaxPart(const MaxPartReport& report, int width, int height);
void writeMaxPartPlot(const std::string& path, const MaxPartReport& report, int width = 1000,
                      int height = 640);

}  // namespace ferry
