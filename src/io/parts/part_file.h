// Part files: what `ferry partition -o DIR` writes and `ferry render DIR`
// loads, one per rank (its instances, with the owner set of each, and the
// objects, meshes, materials and textures they use, re-indexed), plus one
// shared file every rank reads (views, film settings, lights, proxies).
// Binary, little-endian, hashed (XXH64); a loaded part's mesh and texel
// arrays share the file's mapping instead of copying it. Each failed check is
// an InputError naming the file and what is wrong. Layout, checks and what
// each format version added: docs/partitioning.md, "Part files".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "partition/partition.h"
#include "scene/scene.h"

namespace ferry {

// The format written; every format from kOldestPartFormatVersion on is read.
constexpr uint32_t kPartFormatVersion = 15;
constexpr uint32_t kOldestPartFormatVersion = 1;

struct WrittenFile {
  uint64_t bytes = 0;
  uint64_t hash = 0;  // XXH64 of the payload, as in the header
};

// Writes rank `rank`'s part: `instances` (ascending indices into scene) and
// what they use; `owners` per scene instance.
WrittenFile writePartFile(const std::string& path, const Scene& scene,
                          const std::vector<int32_t>& instances, const std::vector<RankSet>& owners,
                          int rank, int ranks);

struct LoadedPart {
  int rank = 0;
  int ranks = 0;
  Scene scene;                  // this part's content only (no views, no lights)
  std::vector<RankSet> owners;  // per instance of `scene`
};
// `expectedHash` (0: not checked) is the payload hash the manifest recorded.
LoadedPart readPartFile(const std::string& path, uint64_t expectedHash = 0);

struct SharedData {
  int ranks = 0;
  std::vector<CameraView> views;
  std::optional<int> filmWidth, filmHeight;
  std::string filmFilename;
  Scene lights;  // see scene/light_scene.h
  std::vector<Proxy> proxies;
  std::vector<ProxyShape> proxyShapes;    // what instanced proxies refer to
  std::vector<Affine3f> proxyPlacements;  // in the order of the instanced proxies
};
WrittenFile writeSharedFile(const std::string& path, const SharedData& shared);
SharedData readSharedFile(const std::string& path, uint64_t expectedHash = 0);

}  // namespace ferry
