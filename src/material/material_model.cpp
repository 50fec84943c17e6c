#include "material/material_model.h"

#include <cmath>

#include "core/error.h"

namespace ferry {

float MaterialRecordReader::number() {
  const float v = pod<float>();
  if (!std::isfinite(v)) fail("a parameter is not a finite number");
  return v;
}

Vec3f MaterialRecordReader::color() {
  const Vec3f c = pod<Vec3f>();
  if (!isFinite(c)) fail("a colour is not finite");
  return c;
}

int32_t MaterialRecordReader::table() {
  const int32_t t = pod<int32_t>();
  if (t != kNoBsdfTable && (t < 0 || size_t(t) >= tables_))
    fail(fmt::format("it names BSDF table {} of {}", t, tables_));
  return t;
}

void MaterialRecordReader::finish() const {
  if (at_ != bytes_.size())
    fail(fmt::format("its record has {} bytes left over", bytes_.size() - at_));
}

void MaterialRecordReader::fail(const std::string& what) const {
  throw InputError(fmt::format("{}: {}", where_, what));
}

}  // namespace ferry
