#include "shapes/spheres.h"

#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

Spheres::Spheres(std::vector<Vec3f> centers, std::vector<float> radii)
    : centers_(std::move(centers)), radii_(std::move(radii)) {
  if (centers_.size() != radii_.size())
    throw InputError(
        fmt::format("spheres: {} centres but {} radii", centers_.size(), radii_.size()));
  if (centers_.size() > UINT32_MAX)
    throw InputError(fmt::format("spheres: {} is more than 2^32 - 1", centers_.size()));
  for (size_t k = 0; k < centers_.size(); ++k)
    if (!isFinite(centers_[k]) || !(radii_[k] > 0) || !std::isfinite(radii_[k]))
      throw InputError(fmt::format("spheres: sphere {} has centre ({}, {}, {}) and radius {}", k,
                                   centers_[k].x, centers_[k].y, centers_[k].z, radii_[k]));
}

Box3f Spheres::primitiveBounds(uint32_t p) const {
  return {centers_[p] - Vec3f(radii_[p]), centers_[p] + Vec3f(radii_[p])};
}

uint64_t Spheres::bytes() const {
  return centers_.capacity() * sizeof(Vec3f) + radii_.capacity() * sizeof(float);
}

namespace {

// The roots of |f + t d|^2 = r^2 (f: the origin relative to the centre),
// with the discriminant formed as Ray Tracing Gems ch. 7 does (b^2 - c loses
// precision when the ray passes far from the centre); false: none.
bool roots(Vec3f f, Vec3f d, float r, float& t0, float& t1) {
  const float a = dot(d, d);
  if (!(a > 0)) return false;
  const float b = -dot(f, d);
  const Vec3f l = f + d * (b / a);
  const float discriminant = a * (r * r - dot(l, l));
  if (!(discriminant >= 0)) return false;
  const float q = b + std::copysign(std::sqrt(discriminant), b);
  if (q == 0) {
    t0 = t1 = 0;
    return true;
  }
  t0 = (dot(f, f) - r * r) / q;
  t1 = q / a;
  if (t0 > t1) std::swap(t0, t1);
  return true;
}

}  // namespace

// The nearer root beyond tnear, refined by solving again from the point it
// gives (far from the centre, |f|^2 - r^2 keeps few of r's bits), if in
// (tnear, tfar). tfar only accepts or rejects: a rank that searches less far
// (another rank's hit is nearer) finds the same t or nothing.
bool Spheres::intersect(uint32_t p, Vec3f origin, Vec3f direction, float tnear, float tfar,
                        float& t, Vec2f& uv) const {
  const Vec3f f = origin - centers_[p];
  const float r = radii_[p];
  float t0, t1;
  if (!roots(f, direction, r, t0, t1)) return false;
  float hit = t0 > tnear ? t0 : t1;
  if (!(hit > tnear)) return false;
  const Vec3f near = f + direction * hit;
  if (float s0, s1; roots(near, direction, r, s0, s1)) {
    const float step = std::abs(s0) < std::abs(s1) ? s0 : s1;
    if (hit + step > tnear) hit += step;
  }
  if (!(hit < tfar)) return false;
  t = hit;
  const Vec3f n = (f + direction * hit) * (1 / r);
  float phi = std::atan2(n.y, n.x);
  if (phi < 0) phi += 2 * kPi;
  // (atan2, not acos: n is not exactly unit, and acos near the poles
  // would turn that into large angles.)
  uv = {phi / (2 * kPi), std::atan2(std::sqrt(n.x * n.x + n.y * n.y), n.z) / kPi};
  return true;
}

ShapeSurface Spheres::surface(uint32_t p, Vec2f uv) const {
  const float phi = uv.x * 2 * kPi, theta = uv.y * kPi;
  const float sinTheta = std::sin(theta);
  const Vec3f n{sinTheta * std::cos(phi), sinTheta * std::sin(phi), std::cos(theta)};
  return {centers_[p] + n * radii_[p], n, n, uv};
}

std::shared_ptr<const Shape> Spheres::subset(std::span<const uint32_t> primitives) const {
  std::vector<Vec3f> centers;
  std::vector<float> radii;
  centers.reserve(primitives.size());
  radii.reserve(primitives.size());
  for (uint32_t p : primitives) {
    centers.push_back(centers_.at(p));
    radii.push_back(radii_[p]);
  }
  return std::make_shared<Spheres>(std::move(centers), std::move(radii));
}

void Spheres::write(RecordWriter& record) const {
  record.array<Vec3f>(centers_);
  record.array<float>(radii_);
}

std::shared_ptr<const Shape> Spheres::read(RecordReader& record) {
  std::vector<Vec3f> centers = record.array<Vec3f>();
  std::vector<float> radii = record.array<float>();
  try {
    return std::make_shared<Spheres>(std::move(centers), std::move(radii));
  } catch (const InputError& e) {
    record.fail(e.what());
  }
}

std::string Spheres::describe() const {
  return fmt::format("{} spheres", centers_.size());
}

}  // namespace ferry
