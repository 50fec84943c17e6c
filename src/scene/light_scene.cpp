#include "scene/light_scene.h"

namespace ferry {

Scene lightScene(const Scene& scene) {
  Scene out;
  out.name = scene.name + " (lights)";
  out.suns = scene.suns;
  out.pointLights = scene.pointLights;
  out.environment = scene.environment;
  std::vector<int32_t> materialOf(scene.materials.size(), -1);
  std::vector<std::vector<int32_t>> emissiveMeshesPerObject(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o)
    for (int32_t m : scene.objects[o].meshes)
      if (scene.materials[scene.meshes[m].material].isEmissive())
        emissiveMeshesPerObject[o].push_back(m);
  for (const Instance& inst : scene.instances) {
    for (int32_t m : emissiveMeshesPerObject[inst.object]) {
      Mesh scratch;
      const Mesh& source = scene.geometry(m, scratch);
      int32_t& material = materialOf[source.material];
      if (material < 0) {
        Material mat = scene.materials[source.material];
        for (int32_t* t : mat.textureSlots()) *t = kNoTexture;
        mat.model = withBsdfTablesRenumbered(  // the light scene holds no tables
            mat.model, [](int32_t) { return kNoBsdfTable; });
        mat.mixedWith = -1;  // emission is the mesh's own material's
        material = out.addMaterial(std::move(mat));
      }
      Mesh mesh;
      mesh.name = source.name;
      mesh.material = material;
      mesh.positions.reserve(source.indices.size() * 3 + 1);
      mesh.indices.reserve(source.indices.size());
      for (const Vec3i& tri : source.indices) {
        const int32_t base = int32_t(mesh.positions.size());
        for (int k = 0; k < 3; ++k)
          mesh.positions.push_back(inst.transform.transformPoint(source.positions[tri[k]]));
        mesh.indices.push_back({base, base + 1, base + 2});
      }
      out.addSingleInstanceMesh(std::move(mesh));
    }
  }
  return out;
}

}  // namespace ferry
