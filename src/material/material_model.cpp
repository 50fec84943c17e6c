#include "material/material_model.h"

#include <cmath>

#include "core/error.h"

namespace ferry {

int32_t MaterialRecordReader::table() {
  const int32_t t = pod<int32_t>();
  if (t != kNoBsdfTable && (t < 0 || size_t(t) >= tables_))
    fail(fmt::format("it names BSDF table {} of {}", t, tables_));
  return t;
}

}  // namespace ferry
