#include "builtin/scene_plan.h"

#include <limits>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "builtin/procedural_texture.h"
#include "core/error.h"

namespace ferry::builtin {

int32_t ScenePlan::addMaterial(Material m) {
  materials.push_back(std::move(m));
  return static_cast<int32_t>(materials.size() - 1);
}

int32_t ScenePlan::addTexture(TextureRecipe t) {
  textures.push_back(std::move(t));
  return static_cast<int32_t>(textures.size() - 1);
}

int32_t ScenePlan::addMesh(MeshRecipe m) {
  meshes.push_back(std::move(m));
  return static_cast<int32_t>(meshes.size() - 1);
}

int32_t ScenePlan::addObject(std::string objectName, std::vector<int32_t> meshIndices) {
  objects.push_back({std::move(objectName), std::move(meshIndices)});
  return static_cast<int32_t>(objects.size() - 1);
}

void ScenePlan::addInstances(int32_t object, uint64_t count,
                             std::function<Affine3f(uint64_t)> transform) {
  batches.push_back({object, count, std::move(transform)});
}

int32_t ScenePlan::addSingleInstanceMesh(MeshRecipe m) {
  std::string objectName = m.name;
  int32_t mesh = addMesh(std::move(m));
  int32_t object = addObject(std::move(objectName), {mesh});
  addInstances(object, 1, [](uint64_t) { return Affine3f::identity(); });
  return object;
}

MeshCounts ScenePlan::objectCounts(int32_t object) const {
  MeshCounts c;
  for (int32_t m : objects[object].meshes) c += meshes[m].counts;
  return c;
}

uint64_t ScenePlan::instanceCount() const {
  uint64_t n = 0;
  for (const InstanceBatch& b : batches) n += b.count;
  return n;
}

int32_t addDiffuseMaterial(ScenePlan& plan, const std::string& name, Vec3f colour, int32_t texture,
                           bool alphaCutout) {
  Material m;
  m.name = name;
  m.baseColor = colour;
  m.baseColorTexture = texture;
  m.alphaTexture = alphaCutout ? texture : kNoTexture;
  return plan.addMaterial(m);
}

void addDaylight(ScenePlan& plan, Vec3f towardsSun, Vec3f zenith, Vec3f horizon, Vec3f below,
                 float belowFade) {
  plan.suns.push_back({normalize(towardsSun), {5.5f, 5.2f, 4.8f}, 0.00465f});
  plan.environmentColor = {1, 1, 1};
  plan.environmentImage = [=] { return skyGradient(zenith, horizon, below, belowFade); };
}

void addStudioDaylightAndView(ScenePlan& plan) {
  addDaylight(plan, {0.6f, 1, 0.8f}, {0.25f, 0.45f, 0.9f}, {0.8f, 0.85f, 0.95f}, {0.3f, 0.3f, 0.3f},
              0.3f);
  CameraView view;
  view.name = "default";
  view.from = {0, 0.8f, 4.2f};
  view.at = {0, 0, 0};
  view.fovY = 40;
  plan.views.push_back(view);
}

void addStudio(ScenePlan& plan, int32_t material, float e, float floorY, float top) {
  MeshRecipe studio;
  studio.name = "studio";
  studio.material = material;
  studio.counts = {6, 4};
  studio.hasNormals = false;
  studio.hasUvs = false;
  studio.build = [=] {
    Mesh m;
    m.positions = {{-e, floorY, e},  {e, floorY, e}, {e, floorY, -e},
                   {-e, floorY, -e}, {e, top, -e},   {-e, top, -e}};
    m.indices = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}, {3, 4, 5}};
    return m;
  };
  plan.addSingleInstanceMesh(std::move(studio));
  plan.bounds.extend(Vec3f(-e, floorY, -e));
  plan.bounds.extend(Vec3f(e, top, e));
}

SceneSummary describePlan(const ScenePlan& plan) {
  // Mirrors summarize() term by term (same per-mesh rounding of the cost
  // model), so the two agree exactly.
  SceneSummary s;
  s.name = plan.name;
  s.uniqueMeshes = plan.meshes.size();
  for (const MeshRecipe& m : plan.meshes) {
    s.triangles += m.counts.triangles;
    s.vertices += m.counts.vertices;
    s.memory += meshCost(m.counts.vertices, m.counts.triangles, m.hasNormals, m.hasUvs);
    if (plan.materials[m.material].isEmissive()) {
      ++s.emissiveMeshes;
      s.emissiveTriangles += m.counts.triangles;
    }
  }
  s.objects = plan.objects.size() + plan.shapes.size();
  for (const InstanceBatch& b : plan.batches) {
    s.instances += b.count;
    s.instancedTriangles += b.count * plan.objectCounts(b.object).triangles;
  }
  s.instances += plan.shapes.size();
  for (const ShapeRecipe& r : plan.shapes) {
    ++s.geometries;
    s.shapePrimitives += r.primitives;
    ++s.shapeKinds[r.kind].geometries;
    s.shapeKinds[r.kind].primitives += r.primitives;
    s.memory += shapeCost(r.primitives * r.piecesPerPrimitive, r.bytes, r.accelBytesPerBox);
  }
  s.memory += instanceCost(s.instances);
  s.textures = plan.textures.size();
  for (const TextureRecipe& t : plan.textures) {
    uint64_t texels = uint64_t(t.width) * uint64_t(t.height);
    s.texels += texels;
    s.memory += textureCost(texels);
  }
  s.suns = plan.suns.size();
  s.environments = plan.environmentImage || maxComponent(plan.environmentColor) > 0 ? 1 : 0;
  s.views = plan.views.size();
  s.media = plan.mediaSummary;
  for (const SceneSummary::Medium& m : plan.mediaSummary) s.memory.media += m.bytes;
  s.memory.media += plan.boundaryBytes;
  s.mediumBoundaries = plan.mediumBoundaries;
  s.boundaryTriangles = plan.boundaryTriangles;
  s.bounds = plan.bounds;
  return s;
}

Scene materializePlan(const ScenePlan& plan, std::shared_ptr<MeshStore> store) {
  constexpr uint64_t kMaxIndex = uint64_t(std::numeric_limits<int32_t>::max());
  for (const MeshRecipe& m : plan.meshes)
    if (m.counts.vertices > kMaxIndex)
      throw InputError(fmt::format(
          "scene '{}': mesh '{}' would have {} vertices, more than 32-bit indices can address; "
          "use a smaller scale (describing the scene still works)",
          plan.name, m.name, m.counts.vertices));

  if (plan.instanceCount() > kMaxIndex)
    throw InputError(fmt::format(
        "scene '{}' would have {} instances, more than 32-bit instance ids can address; use a "
        "smaller scale (describing the scene still works)",
        plan.name, plan.instanceCount()));

  Scene scene;
  scene.name = plan.name;
  scene.materials = plan.materials;

  scene.textures.resize(plan.textures.size());
  scene.meshes.resize(plan.meshes.size());
  // Textures and meshes are independent: one parallel loop over both keeps
  // the two cores busy even when one big terrain dominates.
  const size_t jobs = plan.textures.size() + plan.meshes.size();
  tbb::parallel_for(size_t(0), jobs, [&](size_t job) {
    if (job < plan.textures.size()) {
      const TextureRecipe& r = plan.textures[job];
      Texture t = r.build();
      if (t.width != r.width || t.height != r.height ||
          t.rgba.size() != size_t(r.width) * size_t(r.height) * 4)
        throw InternalError(fmt::format("texture '{}' came out {}x{}, planned {}x{}", r.name,
                                        t.width, t.height, r.width, r.height));
      t.name = r.name;
      scene.textures[job] = std::move(t);
      return;
    }
    const MeshRecipe& r = plan.meshes[job - plan.textures.size()];
    Mesh m = r.build();
    if (m.vertexCount() != r.counts.vertices || m.triangleCount() != r.counts.triangles ||
        m.normals.empty() == r.hasNormals || m.uvs.empty() == r.hasUvs)
      throw InternalError(fmt::format(
          "mesh '{}' came out with {} vertices / {} triangles (normals {}, uvs {}), planned {} / "
          "{} (normals {}, uvs {})",
          r.name, m.vertexCount(), m.triangleCount(), !m.normals.empty(), !m.uvs.empty(),
          r.counts.vertices, r.counts.triangles, r.hasNormals, r.hasUvs));
    m.name = r.name;
    m.material = r.material;
    if (store) store->store(m);
    scene.meshes[job - plan.textures.size()] = std::move(m);
  });

  scene.objects.reserve(plan.objects.size());
  for (const ObjectRecipe& o : plan.objects) scene.objects.push_back({o.name, o.meshes});

  scene.instances.resize(plan.instanceCount());
  uint64_t offset = 0;
  for (const InstanceBatch& b : plan.batches) {
    tbb::parallel_for(tbb::blocked_range<uint64_t>(0, b.count, 1024),
                      [&](const tbb::blocked_range<uint64_t>& range) {
                        for (uint64_t i = range.begin(); i != range.end(); ++i)
                          scene.instances[offset + i] = {b.object, b.transform(i)};
                      });
    offset += b.count;
  }

  for (const ShapeRecipe& r : plan.shapes) {
    std::shared_ptr<const Shape> shape = r.build();
    if (!shape || shape->primitiveCount() != r.primitives || shape->bytes() != r.bytes ||
        shape->kind() != r.kind)
      throw InternalError(
          fmt::format("shape '{}' came out with {} primitives / {} bytes, planned "
                      "{} / {}",
                      r.name, shape ? shape->primitiveCount() : 0, shape ? shape->bytes() : 0,
                      r.primitives, r.bytes));
    scene.addSingleInstanceGeometry({r.name, r.material, std::move(shape)});
  }

  scene.suns = plan.suns;
  scene.environment.color = plan.environmentColor;
  if (plan.environmentImage) scene.environment.image = plan.environmentImage();
  scene.views = plan.views;
  if (plan.makeMedia) plan.makeMedia(scene);
  scene.meshStore = std::move(store);
  return scene;
}

}  // namespace ferry::builtin
