#include "shapes/shape_kinds.h"

#include "core/registry.h"
#include "shapes/curves.h"
#include "shapes/spheres.h"
#include "shapes/unstructured_volume.h"
#include "shapes/volume_brick.h"

namespace ferry {
namespace {

Registry<ShapeKind>& registry() {
  static Registry<ShapeKind> all(
      "geometry kind",
      {
          {"curves",
           "cubic Bézier curve segments with a width at each end, flat, cylinder or ribbon (fur, "
           "hair, grass)",
           Curves::read},
          {"spheres", "analytic spheres, a centre and a radius each (particles, atoms)",
           Spheres::read},
          {"unstructured-volume",
           "tetrahedra with a value at each point through a transfer function, in clusters of "
           "cells; crossings are collisions in its medium",
           UnstructuredVolume::read},
          {"volume-brick",
           "a brick of a grid volume with its ghost layer; crossings are collisions in its medium",
           VolumeBrick::read},
      });
  return all;
}

}  // namespace

const std::deque<ShapeKind>& shapeKinds() {
  return registry().all();
}

const ShapeKind* shapeKind(std::string_view name) {
  return registry().find(name);
}

void registerShapeKind(ShapeKind kind) {
  registry().add(std::move(kind));
}

std::string shapeKindNames() {
  return registry().names();
}

}  // namespace ferry
