#include "scene/scene.h"

#include <algorithm>

#include <fmt/format.h>

#include "core/error.h"
#include "scene/mesh_store.h"

namespace ferry {

Box3f Mesh::bounds() const {
  if (stored) return stored->bounds;
  Box3f b;
  for (const Vec3f& p : positions) b.extend(p);
  return b;
}

std::string Mesh::arrayProblem() const {
  if (!normals.empty() && normals.size() != positions.size())
    return fmt::format("mesh '{}' has {} normals for {} positions", name, normals.size(),
                       positions.size());
  if (!uvs.empty() && uvs.size() != positions.size())
    return fmt::format("mesh '{}' has {} uvs for {} positions", name, uvs.size(), positions.size());
  const auto n = static_cast<int64_t>(positions.size());
  for (size_t t = 0; t < indices.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (indices[t][k] < 0 || indices[t][k] >= n)
        return fmt::format("mesh '{}' triangle {} uses vertex {} of {}", name, t, indices[t][k], n);
  for (size_t v = 0; v < positions.size(); ++v)
    if (!isFinite(positions[v])) return fmt::format("mesh '{}' vertex {} is not finite", name, v);
  return {};
}

const Mesh& Scene::geometry(int32_t m, Mesh& scratch) const {
  const Mesh& mesh = meshes[size_t(m)];
  if (!mesh.stored) return mesh;
  FERRY_CHECK(meshStore != nullptr);
  scratch = meshStore->load(mesh);
  return scratch;
}

Mesh boxMesh(const Box3f& box, std::string name) {
  Mesh m;
  m.name = std::move(name);
  const Vec3f lo = box.lower, hi = box.upper;
  for (int i = 0; i < 8; ++i)
    m.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    m.indices.push_back({f[0], f[1], f[2]});
    m.indices.push_back({f[0], f[2], f[3]});
  }
  return m;
}

int32_t Scene::addSingleInstanceMesh(Mesh mesh) {
  mesh.reserveVertexSlack();
  meshes.push_back(std::move(mesh));
  Object object;
  object.name = meshes.back().name;
  object.meshes.push_back(static_cast<int32_t>(meshes.size() - 1));
  objects.push_back(std::move(object));
  int32_t id = static_cast<int32_t>(objects.size() - 1);
  instances.push_back({id, Affine3f::identity()});
  return id;
}

bool Scene::hasVolumes() const {
  return std::any_of(geometries.begin(), geometries.end(),
                     [](const Geometry& g) { return g.shape && g.shape->isVolume(); });
}

int32_t Scene::addSingleInstanceGeometry(Geometry geometry) {
  geometries.push_back(std::move(geometry));
  Object object;
  object.name = geometries.back().name;
  object.geometries.push_back(static_cast<int32_t>(geometries.size() - 1));
  objects.push_back(std::move(object));
  int32_t id = static_cast<int32_t>(objects.size() - 1);
  instances.push_back({id, Affine3f::identity()});
  return id;
}

void Scene::reserveVertexSlack() {
  for (Mesh& mesh : meshes) mesh.reserveVertexSlack();
}

int32_t Scene::addMaterial(Material material) {
  materials.push_back(std::move(material));
  return static_cast<int32_t>(materials.size() - 1);
}

Box3f Scene::objectBounds(int32_t object) const {
  Box3f b;
  for (int32_t m : objects[object].meshes) b.extend(meshes[m].bounds());
  for (int32_t g : objects[object].geometries)
    if (geometries[g].shape) b.extend(geometries[g].shape->bounds());
  return b;
}

bool Scene::moves() const {
  for (const Instance& inst : instances)
    if (inst.motion) return true;
  for (const CameraView& v : views)
    if (v.motion) return true;
  return false;
}

Box3f Scene::worldBounds() const {
  std::vector<Box3f> perObject(objects.size());
  for (size_t i = 0; i < objects.size(); ++i) perObject[i] = objectBounds(int32_t(i));
  Box3f b;
  for (const Instance& inst : instances) b.extend(inst.placeBox(perObject[inst.object]));
  return b;
}

const CameraView& Scene::view(const std::string& name) const {
  if (views.empty()) throw InputError(fmt::format("scene '{}' has no camera views", this->name));
  if (name.empty()) return views.front();
  std::string known;
  for (const CameraView& v : views) {
    if (v.name == name) return v;
    known += (known.empty() ? "" : ", ") + v.name;
  }
  throw InputError(
      fmt::format("unknown view '{}' in scene '{}' (views: {})", name, this->name, known));
}

std::vector<uint32_t> Scene::instanceCountPerObject() const {
  std::vector<uint32_t> counts(objects.size(), 0);
  for (const Instance& inst : instances) ++counts[inst.object];
  return counts;
}

void Scene::releaseAllBut(const std::vector<int32_t>& keptInstances) {
  std::vector<uint8_t> keepMesh(meshes.size(), 0), keepTexture(textures.size(), 0),
      keepObject(objects.size(), 0), keepTable(bsdfTables.size(), 0);
  for (int32_t i : keptInstances) keepObject[instances[i].object] = 1;
  for (size_t o = 0; o < objects.size(); ++o)
    if (keepObject[o])
      for (int32_t m : objects[o].meshes) {
        keepMesh[m] = 1;
        forEachShadingTexture(meshes[m].material, [&](int32_t t) { keepTexture[size_t(t)] = 1; });
        forEachShadingBsdfTable(meshes[m].material, [&](int32_t t) { keepTable[size_t(t)] = 1; });
      }
  std::vector<uint8_t> keepGeometry(geometries.size(), 0);
  for (size_t o = 0; o < objects.size(); ++o)
    if (keepObject[o])
      for (int32_t g : objects[o].geometries) {
        keepGeometry[g] = 1;
        forEachShadingTexture(geometries[g].material,
                              [&](int32_t t) { keepTexture[size_t(t)] = 1; });
        forEachShadingBsdfTable(geometries[g].material,
                                [&](int32_t t) { keepTable[size_t(t)] = 1; });
      }
  for (size_t g = 0; g < geometries.size(); ++g)
    if (!keepGeometry[g]) geometries[g].shape.reset();
  for (size_t m = 0; m < meshes.size(); ++m)
    if (!keepMesh[m]) meshes[m].releaseArrays();
  for (size_t t = 0; t < textures.size(); ++t)
    if (!keepTexture[t]) textures[t].release();
  for (size_t t = 0; t < bsdfTables.size(); ++t)
    if (!keepTable[t]) bsdfTables[t].reset();
}

void Scene::validate() const {
  auto fail = [&](const std::string& what) {
    throw InputError(fmt::format("scene '{}': {}", name, what));
  };
  auto checkTexture = [&](int32_t t, const std::string& who) {
    if (t != kNoTexture && (t < 0 || size_t(t) >= textures.size()))
      fail(fmt::format("{} refers to texture {} of {}", who, t, textures.size()));
  };
  for (const Material& m : materials) {
    for (int32_t t : m.textures()) checkTexture(t, "material '" + m.name + "'");
    if (!m.model) fail(fmt::format("material '{}' has no model", m.name));
    if (const int32_t t = m.bsdfTable();
        t != kNoBsdfTable && (t < 0 || size_t(t) >= bsdfTables.size()))
      fail(
          fmt::format("material '{}' refers to BSDF table {} of {}", m.name, t, bsdfTables.size()));
    if (m.mixedWith != -1 && (m.mixedWith < 0 || size_t(m.mixedWith) >= materials.size()))
      fail(fmt::format("material '{}' mixes with material {} of {}", m.name, m.mixedWith,
                       materials.size()));
    if (!(m.mixAmount >= 0 && m.mixAmount <= 1))
      fail(fmt::format("material '{}' has a mix amount {} outside [0, 1]", m.name, m.mixAmount));
    if (!isFinite(m.baseColor) || !isFinite(m.emission))
      fail(fmt::format("material '{}' has a non-finite parameter", m.name));
  }
  if (media.size() > 0xfffe) fail(fmt::format("{} media: at most 65534", media.size()));
  auto checkMedium = [&](int32_t m, const std::string& who) {
    if (m != kNoMedium && (m < 0 || size_t(m) >= media.size()))
      fail(fmt::format("{} refers to medium {} of {}", who, m, media.size()));
  };
  auto checkInterface = [&](const MediumInterface& i, const std::string& who) {
    checkMedium(i.inside, who);
    checkMedium(i.outside, who);
  };
  checkMedium(cameraMedium, "the camera");
  for (const MediumBoundary& b : mediumBoundaries) {
    checkInterface(b.media, "medium boundary '" + b.mesh.name + "'");
    if (const std::string problem = b.mesh.arrayProblem(); !problem.empty())
      fail(fmt::format("medium boundary '{}': {}", b.mesh.name, problem));
  }
  for (const Medium& m : media)
    if (!isFinite(m.sigmaA) || !isFinite(m.sigmaS) ||
        std::min({m.sigmaA.x, m.sigmaA.y, m.sigmaA.z, m.sigmaS.x, m.sigmaS.y, m.sigmaS.z}) < 0 ||
        !(std::abs(m.g) < 1) || !isFinite(m.emission))
      fail(
          fmt::format("medium '{}': sigma_a and sigma_s must be finite and not negative, g in "
                      "(-1, 1)",
                      m.name));
  for (const Material& m : materials) {
    size_t steps = 0;
    for (int32_t k = m.mixedWith; k >= 0; k = materials[size_t(k)].mixedWith)
      if (++steps > materials.size()) fail(fmt::format("material '{}' mixes with itself", m.name));
  }

  for (const Mesh& mesh : meshes) {
    if (mesh.material < 0 || size_t(mesh.material) >= materials.size())
      fail(fmt::format("mesh '{}' refers to material {} of {}", mesh.name, mesh.material,
                       materials.size()));
    if (std::string problem = mesh.arrayProblem(); !problem.empty()) fail(problem);
    checkInterface(mesh.media, "mesh '" + mesh.name + "'");
  }
  for (const Geometry& g : geometries) {
    if (g.material < 0 || size_t(g.material) >= materials.size())
      fail(fmt::format("geometry '{}' refers to material {} of {}", g.name, g.material,
                       materials.size()));
    // Lights, cut-outs and bent normals are triangles' (render/lights.h,
    // trace/alpha_cutout.h, render/surface.h).
    forEachShadingMaterial(g.material, [&](int32_t k) {
      const Material& m = materials[size_t(k)];
      const char* what = m.isEmissive()                  ? "emits light"
                         : m.alphaTexture != kNoTexture  ? "has a cut-out"
                         : m.bumpTexture != kNoTexture   ? "has a bump map"
                         : m.normalTexture != kNoTexture ? "has a normal map"
                                                         : nullptr;
      if (what)
        fail(
            fmt::format("geometry '{}' ({}): material '{}' {}, which only triangle meshes can "
                        "have",
                        g.name, g.shape ? std::string(g.shape->kind()) : "released", m.name, what));
    });
  }
  for (const Object& o : objects) {
    for (int32_t m : o.meshes)
      if (m < 0 || size_t(m) >= meshes.size())
        fail(fmt::format("object '{}' refers to mesh {} of {}", o.name, m, meshes.size()));
    for (int32_t g : o.geometries)
      if (g < 0 || size_t(g) >= geometries.size())
        fail(fmt::format("object '{}' refers to geometry {} of {}", o.name, g, geometries.size()));
  }
  for (size_t i = 0; i < instances.size(); ++i) {
    if (instances[i].object < 0 || size_t(instances[i].object) >= objects.size())
      fail(fmt::format("instance {} refers to object {} of {}", i, instances[i].object,
                       objects.size()));
    if (!std::isfinite(instances[i].transform.determinant()) ||
        instances[i].transform.determinant() == 0)
      fail(fmt::format("instance {} has a singular transform", i));
  }
}

bool isCropWindow(float x0, float x1, float y0, float y1) {
  return x0 >= 0 && x0 < x1 && x1 <= 1 && y0 >= 0 && y0 < y1 && y1 <= 1;
}

}  // namespace ferry
