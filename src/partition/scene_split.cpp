#include "partition/scene_split.h"

#include <fmt/format.h>

#include <algorithm>

#include "partition/triangle_clusters.h"
#include "scene/memory_cost.h"
#include "scene/mesh_store.h"
#include "scene/scene.h"

namespace ferry {
namespace {

// The listed triangles of `source` as a mesh of their own: the vertices they
// use (in ascending original order) and the triangles in their original order.
// `remap` is scratch of one entry per source vertex, all -1 on entry and exit.
Mesh extractPiece(const Mesh& source, const std::vector<uint32_t>& triangles, int piece,
                  std::vector<int32_t>& remap) {
  Mesh m;
  m.name = fmt::format("{}#{}", source.name, piece);
  m.material = source.material;
  std::vector<int32_t> used;
  used.reserve(triangles.size() * 3);
  for (uint32_t t : triangles)
    for (int k = 0; k < 3; ++k) used.push_back(source.indices[t][k]);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  m.positions.reserve(used.size() + 1);  // Embree's one element of slack
  for (size_t i = 0; i < used.size(); ++i) {
    remap[used[i]] = int32_t(i);
    m.positions.push_back(source.positions[used[i]]);
    if (!source.normals.empty()) m.normals.push_back(source.normals[used[i]]);
    if (!source.uvs.empty()) m.uvs.push_back(source.uvs[used[i]]);
  }
  m.indices.reserve(triangles.size());
  for (uint32_t t : triangles) {
    const Vec3i& tri = source.indices[t];
    m.indices.push_back({remap[tri.x], remap[tri.y], remap[tri.z]});
  }
  for (int32_t v : used) remap[v] = -1;
  return m;
}

}  // namespace

SceneSplitReport splitForPartitioning(Scene& scene, const SceneSplitOptions& options) {
  SceneSplitReport report;
  const std::vector<uint32_t> instanceCount = scene.instanceCountPerObject();

  // 1. Cut the large meshes that some placed object uses; pieces[m] replaces
  // mesh m (the first piece takes over slot m, the others are appended).
  const size_t meshCount = scene.meshes.size();
  std::vector<std::vector<int32_t>> pieces(meshCount);
  if (options.maxPieceBytes > 0) {
    std::vector<uint8_t> placed(meshCount, 0);
    for (size_t o = 0; o < scene.objects.size(); ++o)
      if (instanceCount[o] > 0)
        for (int32_t m : scene.objects[o].meshes) placed[m] = 1;
    std::vector<int32_t> remap;
    for (size_t m = 0; m < meshCount; ++m) {
      if (!placed[m]) continue;
      const uint64_t cost = meshCost(scene.meshes[m]).total();
      if (cost <= options.maxPieceBytes || scene.meshes[m].triangleCount() < 2) continue;
      const int want = int(std::min<uint64_t>(
          kMaxPiecesPerMesh, (cost + options.maxPieceBytes - 1) / options.maxPieceBytes));
      Mesh scratch;  // a stored mesh is read back, cut, and its pieces stored again
      const Mesh& source = scene.geometry(int32_t(m), scratch);
      std::vector<std::vector<uint32_t>> clusters =
          clusterTriangles(source, Affine3f::identity(), want);
      if (clusters.size() < 2) continue;
      remap.assign(source.positions.size(), -1);
      std::vector<Mesh> made;
      made.reserve(clusters.size());
      for (size_t k = 0; k < clusters.size(); ++k) {
        made.push_back(extractPiece(source, clusters[k], int(k), remap));
        if (scene.meshes[m].stored) scene.meshStore->store(made.back());
      }
      scratch = Mesh{};
      scene.meshes[m] = std::move(made[0]);
      pieces[m].push_back(int32_t(m));
      for (size_t k = 1; k < made.size(); ++k) {
        scene.meshes.push_back(std::move(made[k]));
        pieces[m].push_back(int32_t(scene.meshes.size() - 1));
      }
      ++report.meshesCut;
      report.piecesMade += made.size();
    }
  }

  // 2. Objects: a broken object becomes one object per mesh; each piece of a
  // cut mesh becomes its own object; the rest stays together in the original
  // (with the geometries of other kinds, which are never cut).
  const size_t objectCount = scene.objects.size();
  std::vector<std::vector<int32_t>> replacement(objectCount);
  for (size_t o = 0; o < objectCount; ++o) {
    const bool breakIt = options.breakSingleInstanceObjects && instanceCount[o] == 1 &&
                         scene.objects[o].meshes.size() > 1;
    bool anyCut = false;
    for (int32_t m : scene.objects[o].meshes) anyCut |= !pieces[m].empty();
    if (!breakIt && !anyCut) continue;
    if (breakIt) ++report.objectsBroken;
    const Object original = scene.objects[o];
    std::vector<std::vector<int32_t>> groups;
    std::vector<int32_t> together;
    for (int32_t m : original.meshes) {
      if (!pieces[m].empty()) {
        for (int32_t p : pieces[m]) groups.push_back({p});
      } else if (breakIt) {
        groups.push_back({m});
      } else {
        together.push_back(m);
      }
    }
    if (!together.empty()) groups.insert(groups.begin(), together);
    for (size_t g = 0; g < groups.size(); ++g) {
      Object object;
      object.name = groups[g].size() == 1 && groups.size() > 1
                        ? fmt::format("{}/{}", original.name, scene.meshes[groups[g][0]].name)
                        : original.name;
      object.meshes = groups[g];
      if (g == 0) object.geometries = original.geometries;  // other kinds stay whole, together
      if (g == 0) {
        scene.objects[o] = std::move(object);
        replacement[o].push_back(int32_t(o));
      } else {
        scene.objects.push_back(std::move(object));
        replacement[o].push_back(int32_t(scene.objects.size() - 1));
      }
    }
  }

  // 3. Instances, in order; a replaced object's instance becomes consecutive ones.
  std::vector<Instance> instances;
  instances.reserve(scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const Instance& inst = scene.instances[i];
    if (replacement[inst.object].empty()) {
      instances.push_back(inst);
      report.originalInstance.push_back(int32_t(i));
      continue;
    }
    for (int32_t object : replacement[inst.object]) {
      instances.push_back({object, inst.transform});
      report.originalInstance.push_back(int32_t(i));
    }
  }
  scene.instances = std::move(instances);
  return report;
}

}  // namespace ferry
