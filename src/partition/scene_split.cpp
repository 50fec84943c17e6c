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
  m.media = source.media;
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

// About `want` spatially coherent pieces of the shape's primitives: the
// primitives split at the median of their boxes' centres along the longest
// axis, recursively; each piece lists its primitives in their original order.
void splitPrimitives(std::vector<uint32_t> primitives, const std::vector<Vec3f>& centres, int want,
                     std::vector<std::vector<uint32_t>>& out) {
  if (want <= 1 || primitives.size() < 2) {
    std::sort(primitives.begin(), primitives.end());
    out.push_back(std::move(primitives));
    return;
  }
  Box3f box;
  for (uint32_t p : primitives) box.extend(centres[p]);
  const int axis = box.longestAxis();
  const int left = want / 2;
  const size_t middle = primitives.size() * size_t(left) / size_t(want);
  std::nth_element(primitives.begin(), primitives.begin() + std::ptrdiff_t(middle),
                   primitives.end(), [&](uint32_t a, uint32_t b) {
                     const float ca = centres[a][axis], cb = centres[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  std::vector<uint32_t> low(primitives.begin(), primitives.begin() + std::ptrdiff_t(middle));
  primitives.erase(primitives.begin(), primitives.begin() + std::ptrdiff_t(middle));
  splitPrimitives(std::move(low), centres, left, out);
  splitPrimitives(std::move(primitives), centres, want - left, out);
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

  // 1b. Cut the large geometries of other kinds whose shape can be cut
  // (Shape::subset): gpieces[g] replaces geometry g as meshes' pieces do.
  const size_t geometryCount = scene.geometries.size();
  std::vector<std::vector<int32_t>> gpieces(geometryCount);
  if (options.maxPieceBytes > 0) {
    std::vector<uint8_t> placed(geometryCount, 0);
    for (size_t o = 0; o < scene.objects.size(); ++o)
      if (instanceCount[o] > 0)
        for (int32_t g : scene.objects[o].geometries) placed[g] = 1;
    for (size_t g = 0; g < geometryCount; ++g) {
      const Shape* shape = scene.geometries[g].shape.get();
      if (!placed[g] || !shape || shape->primitiveCount() < 2) continue;
      const uint64_t cost = geometryCost(scene.geometries[g]).total();
      if (cost <= options.maxPieceBytes) continue;
      const int want = int(std::min<uint64_t>(
          kMaxPiecesPerMesh, (cost + options.maxPieceBytes - 1) / options.maxPieceBytes));
      std::vector<Vec3f> centres(shape->primitiveCount());
      std::vector<uint32_t> all(shape->primitiveCount());
      for (uint32_t p = 0; p < shape->primitiveCount(); ++p) {
        centres[p] = shape->primitiveBounds(p).center();
        all[p] = p;
      }
      std::vector<std::vector<uint32_t>> parts;
      splitPrimitives(std::move(all), centres, want, parts);
      std::vector<std::shared_ptr<const Shape>> made;
      for (const auto& part : parts) {
        made.push_back(shape->subset(part));
        if (!made.back()) break;  // the kind cannot be cut
      }
      if (made.size() < 2 || !made.back()) continue;
      const Geometry original = scene.geometries[g];
      for (size_t k = 0; k < made.size(); ++k) {
        Geometry piece{fmt::format("{}#{}", original.name, k), original.material, made[k]};
        if (k == 0) {
          scene.geometries[g] = std::move(piece);
          gpieces[g].push_back(int32_t(g));
        } else {
          scene.geometries.push_back(std::move(piece));
          gpieces[g].push_back(int32_t(scene.geometries.size() - 1));
        }
      }
      ++report.meshesCut;
      report.piecesMade += made.size();
    }
  }

  // 2. Objects: a broken object becomes one object per mesh; each piece of a
  // cut mesh or geometry becomes its own object; the rest stays together in
  // the original (with the uncut geometries of other kinds).
  const size_t objectCount = scene.objects.size();
  std::vector<std::vector<int32_t>> replacement(objectCount);
  for (size_t o = 0; o < objectCount; ++o) {
    const bool breakIt = options.breakSingleInstanceObjects && instanceCount[o] == 1 &&
                         scene.objects[o].meshes.size() > 1;
    bool anyCut = false;
    for (int32_t m : scene.objects[o].meshes) anyCut |= !pieces[m].empty();
    for (int32_t g : scene.objects[o].geometries) anyCut |= !gpieces[g].empty();
    if (!breakIt && !anyCut) continue;
    if (breakIt) ++report.objectsBroken;
    const Object original = scene.objects[o];
    // Each group becomes an object: its meshes and its geometries.
    struct Group {
      std::vector<int32_t> meshes, geometries;
    };
    std::vector<Group> groups;
    Group together;
    for (int32_t m : original.meshes) {
      if (!pieces[m].empty()) {
        for (int32_t p : pieces[m]) groups.push_back({{p}, {}});
      } else if (breakIt) {
        groups.push_back({{m}, {}});
      } else {
        together.meshes.push_back(m);
      }
    }
    std::vector<Group> geometryGroups;
    for (int32_t g : original.geometries) {
      if (!gpieces[g].empty()) {
        for (int32_t p : gpieces[g]) geometryGroups.push_back({{}, {p}});
      } else {
        together.geometries.push_back(g);  // uncut ones stay whole, together
      }
    }
    if (!together.meshes.empty() || !together.geometries.empty())
      groups.insert(groups.begin(), together);
    groups.insert(groups.end(), geometryGroups.begin(), geometryGroups.end());
    for (size_t g = 0; g < groups.size(); ++g) {
      Object object;
      const bool single = groups[g].meshes.size() + groups[g].geometries.size() == 1;
      object.name = single && groups.size() > 1
                        ? fmt::format("{}/{}", original.name,
                                      groups[g].meshes.empty()
                                          ? scene.geometries[size_t(groups[g].geometries[0])].name
                                          : scene.meshes[size_t(groups[g].meshes[0])].name)
                        : original.name;
      object.meshes = groups[g].meshes;
      object.geometries = groups[g].geometries;
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
      instances.push_back({object, inst.transform, inst.motion});
      report.originalInstance.push_back(int32_t(i));
    }
  }
  scene.instances = std::move(instances);
  return report;
}

}  // namespace ferry
