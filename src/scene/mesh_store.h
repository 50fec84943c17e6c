// Mesh arrays out of memory, for partitioning scenes larger than memory
// (`ferry partition --memory-budget`): meshes are written to a spill file as
// they are made and only their counts and bounds stay (Mesh::stored); what
// needs a stored mesh's triangles (cutting, braided proxies, the cover
// check, writing the parts) reads it back with Scene::geometry, one mesh at
// a time.
//
// The file is unlinked as soon as it is created, so it disappears with the
// process however that ends (killed, failed): nothing is left to clean up.
// It is read and written with pread/pwrite, never mapped: its pages live in
// the page cache, which the kernel may drop or write out, and are not the
// process's resident memory.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "scene/scene.h"

namespace ferry {

class MeshStore {
 public:
  // A new, empty spill file at `path` (a unique name: it is unlinked at once).
  explicit MeshStore(const std::string& path);
  ~MeshStore();
  MeshStore(const MeshStore&) = delete;
  MeshStore& operator=(const MeshStore&) = delete;

  // Appends the mesh's arrays to the file and frees them; the mesh keeps its
  // counts and bounds in Mesh::stored. Thread-safe (meshes are made in parallel).
  void store(Mesh& mesh);
  // A copy of a stored mesh with its arrays (and the one element of vertex
  // slack Embree wants); `stored` cleared. Thread-safe.
  Mesh load(const Mesh& stored) const;

  // Bytes written so far.
  uint64_t bytes() const { return end_.load(); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::atomic<uint64_t> end_{0};
};

}  // namespace ferry
