// Part files: what `ferry partition -o DIR` writes and `ferry render DIR`
// loads, one per rank, plus one shared file every rank reads.
//
// Binary, little-endian, in a layout that loads fast: a 64-byte header
// (magic "FERRYPRT", format version, kind, the file's size, an XXH64 hash of
// everything after the header, and a hash of the header itself), then the
// payload: records of fixed-size fields and length-prefixed arrays, each
// array 16-byte aligned in the file, so loading is one memory-mapped pass
// that checks the hash. The mesh and texel arrays are not copied: the loaded
// scene shares them with the mapping (core/shared_array.h), which stays open
// as long as any of them is used, and the Embree backend shares them in turn,
// so a rank holds its part's geometry once (docs/memory.md).
//
// A part holds one rank's content: its instances (in scene order, with the
// mask of every rank holding each), the objects, meshes, materials and
// textures they use, re-indexed. It is written straight from the partitioned
// scene, one part after another, so partitioning never holds a second copy.
// The shared file holds what every rank needs whatever it owns: the camera
// views and film settings, the lights (scene/light_scene.h) and the proxies.
//
// Reading checks, in order: size, magic, version, header hash, kind, the size
// the header states, the payload hash, and the hash the manifest expects;
// each failure is an InputError naming the file and what is wrong.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "partition/partition.h"
#include "scene/scene.h"

namespace ferry {

// Format 2 stores every owner set as rankSetWords(ranks) little-endian 64-bit
// words (ranks 64k .. 64k+63 in word k) and the proxies as boxes then owner
// words, so parts can be made for more than 64 ranks. Format 1 (up to 64
// ranks, one word per set, proxies as 32-byte box+mask records) is still read.
constexpr uint32_t kPartFormatVersion = 8;  // 3: Material::emitsBackSide; 4: coat, sigma;
                                            // 5: solid textures, bump and normal maps, mixes;
                                            // 6: tabulated (Fourier) BSDFs;
                                            // 7: diffuse transmission; 8: instanced proxies
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
