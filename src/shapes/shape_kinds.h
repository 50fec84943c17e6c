// The registry of geometry kinds other than triangle meshes (scene/shape.h):
// each kind by name, with a line of help and how it reads its part-file
// record. The built-in kinds are listed in shape_kinds.cpp; a test or an
// application may register its own.
#pragma once

#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "core/record.h"
#include "scene/shape.h"

namespace ferry {

struct ShapeKind {
  std::string name;
  std::string summary;
  std::function<std::shared_ptr<const Shape>(RecordReader&)> read;
};

// Every kind, the built-in ones first.
const std::deque<ShapeKind>& shapeKinds();
// Null if none has that name.
const ShapeKind* shapeKind(std::string_view name);
// Adds a kind; a name already taken is an InternalError.
void registerShapeKind(ShapeKind kind);
// Every kind's name, "a, b, c".
std::string shapeKindNames();

}  // namespace ferry
