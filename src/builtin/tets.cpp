#include "builtin/tets.h"

#include <algorithm>
#include <cmath>

#include "shapes/unstructured_volume.h"

namespace ferry::builtin {

float tetsField(Vec3f p) {
  const float ball = std::clamp(1.15f - length(p) / 0.8f, 0.0f, 1.0f);
  const float ripple = 0.75f + 0.25f * std::sin(6 * p.x) * std::sin(5 * p.y) * std::sin(7 * p.z);
  return std::clamp(ball * ripple, 0.0f, 1.0f);
}

uint32_t tetsCubesPerSide(uint64_t count) {
  return std::max<uint32_t>(1, uint32_t(std::lround(std::cbrt(double(count) / 6))));
}

ScenePlan planTets(uint64_t count, uint32_t /*seed: the lattice has no randomness*/) {
  ScenePlan plan;
  plan.name = "tets";
  const uint32_t n = tetsCubesPerSide(count);
  const uint64_t points = uint64_t(n + 1) * (n + 1) * (n + 1), cells = uint64_t(n) * n * n * 6;
  const int32_t grey = addDiffuseMaterial(plan, "studio", Vec3f(0.5f));
  addStudio(plan, grey, 3, -1.2f, 3);

  ShapeRecipe volume;
  volume.name = "tets";
  volume.kind = "unstructured-volume";
  volume.material = grey;
  volume.primitives = (cells + kCellsPerCluster - 1) / kCellsPerCluster;
  volume.bytes = UnstructuredVolume::bytesFor(points, cells, volume.primitives);
  volume.build = [=] {
    std::vector<Vec3f> position(points);
    std::vector<float> value(points);
    const auto index = [n](uint32_t x, uint32_t y, uint32_t z) {
      return uint32_t((uint64_t(z) * (n + 1) + y) * (n + 1) + x);
    };
    for (uint32_t z = 0; z <= n; ++z)
      for (uint32_t y = 0; y <= n; ++y)
        for (uint32_t x = 0; x <= n; ++x) {
          const Vec3f p = Vec3f(float(x), float(y), float(z)) * (2.0f / float(n)) - Vec3f(1);
          position[index(x, y, z)] = p;
          value[index(x, y, z)] = tetsField(p);
        }
    // Six tetrahedra a cube, each from corner 0 to corner 7 along one order
    // of the axes: the same cut in every cube, so faces match.
    constexpr int kOrders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                   {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    std::vector<UnstructuredVolume::Tet> tets;
    tets.reserve(cells);
    for (uint32_t z = 0; z < n; ++z)
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x)
          for (const auto& order : kOrders) {
            uint32_t c[3] = {x, y, z};
            UnstructuredVolume::Tet t;
            t[0] = index(c[0], c[1], c[2]);
            for (int k = 0; k < 3; ++k) {
              ++c[order[k]];
              t[size_t(k) + 1] = index(c[0], c[1], c[2]);
            }
            tets.push_back(t);
          }
    TransferFunction tf = TransferFunction::standard();
    tf = tf.withScale(tf.scale() / 2);  // mean free paths across the 2-unit box at opacity 1
    return UnstructuredVolume::make(std::move(position), std::move(value), std::move(tets),
                                    std::make_shared<const TransferFunction>(std::move(tf)));
  };
  plan.shapes.push_back(std::move(volume));

  addStudioDaylightAndView(plan);
  return plan;
}

}  // namespace ferry::builtin
