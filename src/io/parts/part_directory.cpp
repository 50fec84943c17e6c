#include "io/parts/part_directory.h"

#include <fmt/format.h>

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/error.h"
#include "core/fault_injection.h"
#include "io/parts/part_file.h"
#include "scene/scene_summary.h"

namespace ferry {
namespace {

std::string join(const std::string& directory, const std::string& file) {
  return (std::filesystem::path(directory) / file).string();
}

namespace fs = std::filesystem;

// Temporary directories of earlier runs that were killed (their process is
// gone): ".NAME.tmp.PID" next to the target.
void removeStaleTemporaries(const fs::path& parent, const std::string& name) {
  std::error_code ec;
  const std::string prefix = "." + name + ".tmp.";
  for (const auto& entry : fs::directory_iterator(parent, ec)) {
    const std::string file = entry.path().filename().string();
    if (file.rfind(prefix, 0) != 0) continue;
    const long pid = std::strtol(file.c_str() + prefix.size(), nullptr, 10);
    if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove_all(entry.path(), ec);
  }
}

// Makes `temporary` the directory `target`: renamed onto it if there is
// none, else atomically exchanged with it (renameat2 RENAME_EXCHANGE) and
// the old one, now at `temporary`, removed. Readers see the old directory or
// the new one, never a mix or none.
void replaceDirectory(const fs::path& temporary, const fs::path& target) {
  std::error_code ec;
  if (!fs::exists(target, ec)) {
    fs::rename(temporary, target, ec);
    if (ec)
      throw InputError(fmt::format("{}: cannot rename the finished parts into place ({})",
                                   target.string(), ec.message()));
    return;
  }
  if (::renameat2(AT_FDCWD, temporary.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) != 0)
    throw InputError(fmt::format("{}: cannot swap the finished parts into place ({})",
                                 target.string(), std::strerror(errno)));
  fs::remove_all(temporary, ec);  // the old directory
}

// Writes the whole directory into `directory` (empty, new).
Manifest writeParts(const std::string& directory, const Scene& scene, const Partition& partition,
                    const Scene& lights, const PartDirectoryInfo& info);

}  // namespace

std::string partFileName(int rank) {
  return fmt::format("part-{:04d}.fpart", rank);
}

Manifest writePartDirectory(const std::string& directory, const Scene& scene,
                            const Partition& partition, const Scene& lights,
                            const PartDirectoryInfo& info) {
  FERRY_CHECK_EQ(partition.instanceOwners.size(), scene.instances.size());
  // Everything goes into a temporary directory next to the target, which
  // replaces it only when complete: an interrupted or failed partition
  // (disk full, bad input, killed) leaves the previous directory as it was
  // and no half-written one (a killed run's temporary is removed by the next).
  fs::path target = fs::absolute(fs::path(directory)).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();
  std::error_code ec;
  if (fs::exists(target, ec)) {
    if (!fs::is_directory(target, ec))
      throw InputError(fmt::format("{}: exists and is not a directory", directory));
    if (!fs::is_empty(target, ec) && !isPartDirectory(target.string()))
      throw InputError(
          fmt::format("{}: exists and is not a part directory (no {}): not replacing it", directory,
                      kManifestName));
  }
  const fs::path parent = target.parent_path();
  fs::create_directories(parent, ec);
  removeStaleTemporaries(parent, target.filename().string());
  const fs::path temporary =
      parent / fmt::format(".{}.tmp.{}", target.filename().string(), ::getpid());
  fs::remove_all(temporary, ec);
  if (!fs::create_directory(temporary, ec))
    throw InputError(fmt::format("{}: cannot create a directory next to it ({})", directory,
                                 ec ? ec.message() : "exists"));
  try {
    Manifest m = writeParts(temporary.string(), scene, partition, lights, info);
    replaceDirectory(temporary, target);
    return m;
  } catch (...) {
    fs::remove_all(temporary, ec);
    throw;
  }
}

namespace {

Manifest writeParts(const std::string& directory, const Scene& scene, const Partition& partition,
                    const Scene& lights, const PartDirectoryInfo& info) {
  Manifest m;
  m.version = kPartFormatVersion;
  m.scene = info.scene;
  m.partitioner = info.partitioner;
  m.options = info.options;
  m.ranks = partition.ranks;
  m.summary = info.summary;
  m.inputBytes = info.inputBytes;
  m.replicatedBytes = info.replicatedBytes;
  m.proxies = partition.proxies.size();
  m.partitionSeconds = info.partitionSeconds;
  m.filmScale = scene.filmScale;
  m.filmMaxSampleLuminance = scene.filmMaxSampleLuminance;
  m.filmMaxComponentValue = scene.filmMaxComponentValue;
  m.filmCrop = scene.filmCrop;
  m.integrator = scene.integrator;
  m.integratorMaxDepth = scene.integratorMaxDepth;
  m.shutterOpen = scene.shutterOpen, m.shutterClose = scene.shutterClose;
  m.motionStart = scene.motionStart, m.motionEnd = scene.motionEnd;
  for (int r = 0; r < partition.ranks; ++r) {
    const std::vector<int32_t> owned = partition.instancesOf(r);
    ManifestPart p;
    p.rank = r;
    p.file = partFileName(r);
    p.instances = owned.size();
    p.estimatedBytes = ownedMemory(scene, owned).total();
    WrittenFile w = writePartFile(join(directory, p.file), scene, owned, partition.instanceOwners,
                                  r, partition.ranks);
    p.bytes = w.bytes;
    p.hash = w.hash;
    m.parts.push_back(std::move(p));
    maybeInjectFailure("partition-write", r);  // tests: a failure after part r is written
  }
  SharedData shared;
  shared.ranks = partition.ranks;
  shared.views = scene.views;
  shared.filmWidth = scene.filmWidth;
  shared.filmHeight = scene.filmHeight;
  shared.filmFilename = scene.filmFilename;
  shared.lights = lights;
  shared.proxies = partition.proxies;
  shared.proxyShapes = partition.proxyShapes;
  shared.proxyPlacements = partition.proxyPlacements;
  m.shared.file = "shared.fpart";
  WrittenFile w = writeSharedFile(join(directory, m.shared.file), shared);
  m.shared.bytes = w.bytes;
  m.shared.hash = w.hash;
  writeManifest(directory, m);
  return m;
}

}  // namespace

RankPart loadRankPart(const std::string& directory, int rank, int ranks) {
  RankPart out;
  out.manifest = readManifest(directory);
  const Manifest& m = out.manifest;
  if (m.ranks != ranks)
    throw InputError(fmt::format(
        "{}: partitioned for {} ranks, but {} ranks are running (run with mpirun -np {}, "
        "or partition again for {})",
        join(directory, kManifestName), m.ranks, ranks, m.ranks, ranks));
  SharedData shared = readSharedFile(join(directory, m.shared.file), m.shared.hash);
  if (shared.ranks != ranks)
    throw InputError(fmt::format("{}: made for {} ranks", m.shared.file, shared.ranks));
  LoadedPart part = readPartFile(join(directory, m.parts[rank].file), m.parts[rank].hash);
  if (part.rank != rank || part.ranks != ranks)
    throw InputError(fmt::format("{}: holds rank {} of {}, not rank {} of {}",
                                 join(directory, m.parts[rank].file), part.rank, part.ranks, rank,
                                 ranks));
  out.scene = std::move(part.scene);
  out.scene.views = std::move(shared.views);
  out.scene.filmWidth = shared.filmWidth;
  out.scene.filmHeight = shared.filmHeight;
  out.scene.filmFilename = shared.filmFilename;
  out.partition.ranks = ranks;
  out.partition.instanceOwners = std::move(part.owners);
  out.partition.proxies = std::move(shared.proxies);
  out.partition.proxyShapes = std::move(shared.proxyShapes);
  out.partition.proxyPlacements = std::move(shared.proxyPlacements);
  out.lights = std::move(shared.lights);
  return out;
}

Scene loadAllParts(const std::string& directory, Partition& partition) {
  const Manifest m = readManifest(directory);
  SharedData shared = readSharedFile(join(directory, m.shared.file), m.shared.hash);
  Scene all;
  all.name = m.summary.value("name", std::string());
  all.views = shared.views;
  partition = Partition{};
  partition.ranks = m.ranks;
  partition.proxies = shared.proxies;
  partition.proxyShapes = shared.proxyShapes;
  partition.proxyPlacements = shared.proxyPlacements;
  for (const ManifestPart& p : m.parts) {
    LoadedPart part = readPartFile(join(directory, p.file), p.hash);
    const int32_t tables = int32_t(all.bsdfTables.size()), textures = int32_t(all.textures.size()),
                  materials = int32_t(all.materials.size()), meshes = int32_t(all.meshes.size()),
                  objects = int32_t(all.objects.size());
    for (Texture& t : part.scene.textures) all.textures.push_back(std::move(t));
    for (auto& t : part.scene.bsdfTables) all.bsdfTables.push_back(std::move(t));
    for (Material mat : part.scene.materials) {
      for (int32_t* t : mat.textureSlots())
        if (*t != kNoTexture) *t += textures;
      mat.model = withBsdfTablesRenumbered(mat.model, [&](int32_t t) { return t + tables; });
      if (mat.mixedWith >= 0) mat.mixedWith += materials;
      all.materials.push_back(std::move(mat));
    }
    for (Mesh& mesh : part.scene.meshes) {
      mesh.material += materials;
      all.meshes.push_back(std::move(mesh));
    }
    const int32_t geometries = int32_t(all.geometries.size());
    for (Geometry& g : part.scene.geometries) {
      g.material += materials;
      all.geometries.push_back(std::move(g));
    }
    for (Object& o : part.scene.objects) {
      for (int32_t& mesh : o.meshes) mesh += meshes;
      for (int32_t& g : o.geometries) g += geometries;
      all.objects.push_back(std::move(o));
    }
    for (const Instance& inst : part.scene.instances)
      all.instances.push_back({inst.object + objects, inst.transform, inst.motion});
    partition.instanceOwners.insert(partition.instanceOwners.end(), part.owners.begin(),
                                    part.owners.end());
  }
  return all;
}

}  // namespace ferry
