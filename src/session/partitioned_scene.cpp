#include "session/partitioned_scene.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include <fmt/format.h>

#include "core/error.h"
#include "io/parts/part_file.h"
#include "partition/proxies.h"
#include "partition/units.h"
#include "scene/light_scene.h"
#include "scene/scene_summary.h"

#include "io/parts/part_directory.h"
#include "io/scene_loader.h"
#include "partition/partitioner.h"

namespace ferry {

PartitionedScene loadPartitionedScene(const SessionSettings& settings, int ranks, int rank,
                                      Scene* given,
                                      const std::function<void(Scene&)>& beforePartition) {
  PartitionedScene out;
  if (!given && isPartDirectory(settings.scene)) {
    if (rank >= 0) {
      RankPart part = loadRankPart(settings.scene, rank, ranks);
      out.scene = std::move(part.scene);
      out.partition = std::move(part.partition);
      out.lights = std::move(part.lights);
      out.manifest = std::move(part.manifest);
    } else {
      out.scene = loadAllParts(settings.scene, out.partition);
      out.manifest = readManifest(settings.scene);
    }
    out.partitioner = out.manifest->partitioner;
    return out;
  }
  out.scene = given ? std::move(*given) : loadScene(settings.scene, settings.load);
  if (beforePartition) beforePartition(out.scene);
  const PartitionerOptions options = partitionerOptions(settings, ranks);
  out.partition = partitionScene(out.scene, ranks, options);
  out.partitioner = options.chosen().name();
  return out;
}

namespace {

// Every rank's `mine` on every rank, in rank order (collective).
std::vector<std::string> allGather(const Communicator& comm, const std::string& mine) {
  std::vector<int> lengths = comm.gatherInt(int(mine.size()));
  lengths.resize(size_t(comm.size()));
  comm.broadcastBytes(std::as_writable_bytes(std::span(lengths)));
  std::vector<int> offsets(lengths.size(), 0);
  size_t total = 0;
  for (size_t r = 0; r < lengths.size(); ++r) {
    offsets[r] = int(total);
    total += size_t(lengths[r]);
  }
  std::string all(total, '\0');
  comm.gatherBytes(mine.data(), int(mine.size()), all.data(), lengths, offsets);
  comm.broadcastBytes(std::as_writable_bytes(std::span(all.data(), all.size())));
  std::vector<std::string> out;
  for (size_t r = 0; r < lengths.size(); ++r) out.push_back(all.substr(offsets[r], lengths[r]));
  return out;
}

// The shared data of one piece goes between ranks as a shared part file's
// bytes (io/parts/part_file.h: one serialization for lights and proxies).
std::string sharedBytes(const SharedData& shared, int rank) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     fmt::format("ferry-piece-{}-{}.fpart", getpid(), rank);
  writeSharedFile(path.string(), shared);
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove(path);
  return bytes;
}

SharedData sharedFromBytes(const std::string& bytes, int rank, int from) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      fmt::format("ferry-piece-{}-{}-from-{}.fpart", getpid(), rank, from);
  {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
  }
  SharedData shared = readSharedFile(path.string());
  std::filesystem::remove(path);
  return shared;
}

// `lights` appended to `all` (materials re-indexed), as lightScene orders them.
void appendLights(Scene& all, Scene&& lights) {
  const int32_t materials = int32_t(all.materials.size());
  for (Material& m : lights.materials) all.materials.push_back(std::move(m));
  for (Mesh& mesh : lights.meshes) {
    mesh.material += materials;
    all.addSingleInstanceMesh(std::move(mesh));
  }
}

// The whole's summary: the pieces' counts summed; what every rank holds alike
// (lights other than emitters, views, media) is the piece's own.
SceneSummary wholeSummary(const SceneSummary& piece, const Communicator& comm) {
  SceneSummary whole = piece;
  uint64_t* fields[] = {
      &whole.uniqueMeshes,      &whole.geometries,       &whole.shapePrimitives,
      &whole.volumeBricks,      &whole.triangles,        &whole.vertices,
      &whole.objects,           &whole.instances,        &whole.instancedTriangles,
      &whole.textures,          &whole.texels,           &whole.emissiveMeshes,
      &whole.emissiveTriangles, &whole.memory.vertices,  &whole.memory.normals,
      &whole.memory.uvs,        &whole.memory.indices,   &whole.memory.texels,
      &whole.memory.shapes,     &whole.memory.instances, &whole.memory.accel,
      &whole.movingInstances};
  std::vector<uint64_t> counts;
  for (uint64_t* f : fields) counts.push_back(*f);
  counts = comm.sum(std::span<const uint64_t>(counts));
  for (size_t i = 0; i < counts.size(); ++i) *fields[i] = counts[i];
  whole.bounds = wholeBounds(piece.bounds, comm);
  return whole;
}

}  // namespace

Box3f wholeBounds(const Box3f& box, const Communicator& comm) {
  // Maxima of -lower and upper; an empty box contributes the lowest double.
  const double none = std::numeric_limits<double>::lowest();
  const bool empty = box.empty();
  std::vector<double> mine(6, none);
  if (!empty)
    mine = {-double(box.lower.x), -double(box.lower.y), -double(box.lower.z),
            double(box.upper.x),  double(box.upper.y),  double(box.upper.z)};
  const std::vector<double> m = comm.max(std::span<const double>(mine));
  if (m[0] == none) return Box3f{};
  return Box3f{{-float(m[0]), -float(m[1]), -float(m[2])}, {float(m[3]), float(m[4]), float(m[5])}};
}

PartitionedScene distributedPiece(Scene piece, const Communicator& comm) {
  const int rank = comm.rank(), ranks = comm.size();
  std::string error;
  SharedData mine;
  try {
    piece.validate();
    mine.ranks = ranks;
    mine.lights = lightScene(piece);
    // The partitioners' proxies for what this rank holds: a mesh placed once
    // braided into boxes (as many as the partitioners' default), an
    // instance of an instanced object its box.
    const UnitSet units = extractUnits(piece, UnitOptions{});
    const std::vector<RankSet> owners(units.units.size(), RankSet::single(rank));
    mine.proxies = instanceProxies(piece, units, owners, PartitionerOptions{}.meshProxies, 1);
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (const std::string failure = comm.failureMessage(!error.empty(), error); !failure.empty())
    throw InputError(failure);
  const std::vector<std::string> pieces = allGather(comm, sharedBytes(mine, rank));

  PartitionedScene out;
  out.partition.ranks = ranks;
  out.partition.instanceOwners.assign(piece.instances.size(), RankSet::single(rank));
  out.lights.name = piece.name + " (lights)";
  out.lights.suns = piece.suns;
  out.lights.pointLights = piece.pointLights;
  out.lights.environment = piece.environment;
  for (int r = 0; r < ranks; ++r) {
    SharedData shared = r == rank ? std::move(mine) : sharedFromBytes(pieces[size_t(r)], rank, r);
    appendLights(out.lights, std::move(shared.lights));
    for (Proxy& p : shared.proxies) out.partition.proxies.push_back(p);
  }
  Manifest manifest;
  manifest.scene = piece.name;
  manifest.partitioner = "distributed";
  manifest.ranks = ranks;
  manifest.summary = wholeSummary(summarize(piece), comm).toJson();
  manifest.filmScale = piece.filmScale;
  manifest.filmMaxSampleLuminance = piece.filmMaxSampleLuminance;
  manifest.filmMaxComponentValue = piece.filmMaxComponentValue;
  manifest.filmCrop = piece.filmCrop;
  manifest.integrator = piece.integrator;
  manifest.integratorMaxDepth = piece.integratorMaxDepth;
  manifest.shutterOpen = piece.shutterOpen, manifest.shutterClose = piece.shutterClose;
  manifest.motionStart = piece.motionStart, manifest.motionEnd = piece.motionEnd;
  out.partitioner = manifest.partitioner;
  out.manifest = std::move(manifest);
  out.scene = std::move(piece);
  return out;
}

}  // namespace ferry
