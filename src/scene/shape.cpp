#include "scene/shape.h"

namespace ferry {

Box3f Shape::bounds() const {
  Box3f b;
  for (uint32_t p = 0; p < primitiveCount(); ++p) b.extend(primitiveBounds(p));
  return b;
}

}  // namespace ferry
