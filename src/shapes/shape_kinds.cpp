#include "shapes/shape_kinds.h"

#include <mutex>

#include <fmt/format.h>

#include "core/error.h"
#include "shapes/spheres.h"

namespace ferry {
namespace {

std::deque<ShapeKind>& kinds() {
  static std::deque<ShapeKind> all = {
      {"spheres", "analytic spheres, a centre and a radius each (particles, atoms)", Spheres::read},
  };
  return all;
}

std::mutex& registryMutex() {
  static std::mutex m;
  return m;
}

}  // namespace

const std::deque<ShapeKind>& shapeKinds() {
  return kinds();
}

const ShapeKind* shapeKind(std::string_view name) {
  std::lock_guard lock(registryMutex());
  for (const ShapeKind& k : kinds())
    if (k.name == name) return &k;
  return nullptr;
}

void registerShapeKind(ShapeKind kind) {
  std::lock_guard lock(registryMutex());
  for (const ShapeKind& k : kinds())
    if (k.name == kind.name)
      throw InternalError(fmt::format("geometry kind \"{}\" is registered twice", kind.name));
  kinds().push_back(std::move(kind));
}

}  // namespace ferry
