// How a scene file is loaded and how the loaders talk back while they work:
// the choices a user makes on the command line (--env-fallback), warnings
// about what was skipped or approximated, and progress on large inputs.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>

namespace ferry {

class MeshStore;

struct LoadOptions {
  // A missing environment map (pbrt's `LightSource "infinite" "mapname"`) is
  // an error naming the file; with this set it becomes a constant white
  // environment (times the light's scale) and a warning instead.
  bool envFallback = false;
  // The array a VTK file is rendered by (--field): a .vti's values, a .vtp's
  // radius; empty: the file's own choice (io/volumes/volume_files.h).
  std::string field;
  // Where warnings go; empty: "ferry: warning: ..." on stderr.
  std::function<void(const std::string&)> warn;
  // Progress on large inputs (bytes of the current file read, its size, its
  // name). Called at most about a hundred times per file; empty: silent.
  std::function<void(uint64_t done, uint64_t total, const std::string& what)> progress;
  // The most triangles one generated shape (pbrt's loopsubdiv) may have;
  // more is an InputError naming the shape, not a huge allocation.
  uint64_t maxGeneratedTriangles = uint64_t(1) << 26;
  // Out-of-core loading (ferry partition --memory-budget): meshes go to this
  // store as they are finished (built-ins as generated, pbrt shapes and
  // plymesh files as parsed), so the scene's geometry is never all in
  // memory. OBJ, glTF and a lone PLY are read whole first, then stored.
  std::shared_ptr<MeshStore> meshStore;
};

// Warnings of one load, each said once: a pbrt file with a million shapes
// using one unsupported parameter gets one line, not a million.
class LoadWarnings {
 public:
  explicit LoadWarnings(const LoadOptions& options) : options_(options) {}
  // Says `message` unless a warning with the same `key` was already said.
  void once(const std::string& key, const std::string& message);
  // Keyed by the message itself.
  void once(const std::string& message) { once(message, message); }
  size_t count() const { return said_.size(); }

 private:
  const LoadOptions& options_;
  std::mutex mutex_;
  std::set<std::string> said_;
};

// Reports the progress of reading one file through LoadOptions::progress,
// rate-limited to about every 1% and only for files of at least `minimumBytes`.
class LoadProgress {
 public:
  LoadProgress(const LoadOptions& options, std::string what, uint64_t totalBytes,
               uint64_t minimumBytes = uint64_t(32) << 20);
  void update(uint64_t doneBytes);
  void finish();

 private:
  const LoadOptions& options_;
  std::string what_;
  uint64_t total_;
  uint64_t step_;
  uint64_t next_;
  bool enabled_;
};

}  // namespace ferry
