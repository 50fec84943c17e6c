#include "core/record.h"

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

float RecordReader::number() {
  const float v = pod<float>();
  if (!std::isfinite(v)) fail("a parameter is not a finite number");
  return v;
}

Vec3f RecordReader::color() {
  const Vec3f c = pod<Vec3f>();
  if (!isFinite(c)) fail("a colour or point is not finite");
  return c;
}

void RecordReader::finish() const {
  if (at_ != bytes_.size())
    fail(fmt::format("its record has {} bytes left over", bytes_.size() - at_));
}

void RecordReader::fail(const std::string& what) const {
  throw InputError(fmt::format("{}: {}", where_, what));
}

}  // namespace ferry
