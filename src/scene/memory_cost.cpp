#include "scene/memory_cost.h"

#include "material/fourier_bsdf_table.h"

#include "core/math.h"
#include "scene/scene.h"

namespace ferry {

MemoryCost& MemoryCost::operator+=(const MemoryCost& o) {
  vertices += o.vertices;
  normals += o.normals;
  uvs += o.uvs;
  indices += o.indices;
  texels += o.texels;
  instances += o.instances;
  accel += o.accel;
  shapes += o.shapes;
  media += o.media;
  return *this;
}

MemoryCost MemoryCost::scaled(uint64_t times) const {
  MemoryCost c = *this;
  c.vertices *= times;
  c.normals *= times;
  c.uvs *= times;
  c.indices *= times;
  c.texels *= times;
  c.instances *= times;
  c.accel *= times;
  c.shapes *= times;
  c.media *= times;
  return c;
}

MemoryCost meshCost(uint64_t vertexCount, uint64_t triangleCount, bool hasNormals, bool hasUvs) {
  MemoryCost c;
  c.vertices = vertexCount * sizeof(Vec3f);
  c.normals = hasNormals ? vertexCount * sizeof(Vec3f) : 0;
  c.uvs = hasUvs ? vertexCount * sizeof(Vec2f) : 0;
  c.indices = triangleCount * sizeof(Vec3i);
  // A mesh without triangles is never given to Embree.
  if (triangleCount > 0)
    c.accel = static_cast<uint64_t>(double(triangleCount) * MemoryModel::kAccelBytesPerTriangle +
                                    MemoryModel::kAccelBytesPerMesh);
  return c;
}

MemoryCost meshCost(const Mesh& mesh) {
  return meshCost(mesh.vertexCount(), mesh.triangleCount(), mesh.hasNormals(), mesh.hasUvs());
}

MemoryCost textureCost(uint64_t texelCount) {
  MemoryCost c;
  c.texels = texelCount * 4;
  return c;
}

MemoryCost textureCost(const Texture& texture) {
  uint64_t texels = texture.texelCount();
  for (const Texture& part : texture.parts) texels += textureCost(part).texels / 4;
  return textureCost(texels);
}

MemoryCost bsdfTableCost(const FourierBsdfTable& table) {
  MemoryCost c;
  c.texels = table.bytes();
  return c;
}

MemoryCost instanceCost(uint64_t instanceCount) {
  MemoryCost c;
  c.instances = static_cast<uint64_t>(instanceCount * MemoryModel::kBytesPerInstanceRecord);
  c.accel = static_cast<uint64_t>(instanceCount * MemoryModel::kAccelBytesPerInstance);
  return c;
}

MemoryCost geometryCost(const Geometry& geometry) {
  if (!geometry.shape) return {};
  const Shape& shape = *geometry.shape;
  if (!shape.flatCurves().points.empty())
    return shapeCost(shape.primitiveCount(), shape.bytes(), MemoryModel::kAccelBytesPerFlatCurve);
  return shapeCost(uint64_t(shape.primitiveCount()) * shape.piecesPerPrimitive(), shape.bytes());
}

MemoryCost shapeCost(uint64_t boxes, uint64_t bytes, double accelBytesPerBox) {
  MemoryCost c;
  c.shapes = bytes;
  c.accel =
      static_cast<uint64_t>(double(boxes) * accelBytesPerBox + MemoryModel::kAccelBytesPerMesh);
  return c;
}

MemoryCost mediaCost(const Scene& scene) {
  MemoryCost c;
  for (const Medium& m : scene.media) c.media += m.bytes();
  for (const MediumBoundary& b : scene.mediumBoundaries) c.media += meshCost(b.mesh).total();
  return c;
}

}  // namespace ferry
