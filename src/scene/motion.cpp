#include "scene/motion.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace ferry {
namespace {

using Quat = std::array<double, 4>;  // x, y, z, w
using Mat3 = std::array<std::array<double, 3>, 3>;

Mat3 linearOf(const Affine3f& a) {
  Mat3 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m[r][c] = a.l[r][c];
  return m;
}

Mat3 multiply(const Mat3& a, const Mat3& b) {
  Mat3 m{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) m[r][c] += a[r][k] * b[k][c];
  return m;
}

double determinant(const Mat3& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Mat3 inverse(const Mat3& m) {
  const double d = 1 / determinant(m);
  Mat3 r;
  r[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * d;
  r[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * d;
  r[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * d;
  r[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * d;
  r[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * d;
  r[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * d;
  r[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * d;
  r[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * d;
  r[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * d;
  return r;
}

Quat quaternionOf(const Mat3& m) {
  const double trace = m[0][0] + m[1][1] + m[2][2];
  Quat q;
  if (trace > 0) {
    const double s = std::sqrt(trace + 1) * 2;
    q = {(m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, s / 4};
  } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
    const double s = std::sqrt(1 + m[0][0] - m[1][1] - m[2][2]) * 2;
    q = {s / 4, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s};
  } else if (m[1][1] > m[2][2]) {
    const double s = std::sqrt(1 + m[1][1] - m[0][0] - m[2][2]) * 2;
    q = {(m[0][1] + m[1][0]) / s, s / 4, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s};
  } else {
    const double s = std::sqrt(1 + m[2][2] - m[0][0] - m[1][1]) * 2;
    q = {(m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, s / 4, (m[1][0] - m[0][1]) / s};
  }
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& c : q) c /= n;
  return q;
}

Vec3f rotate(const Mat3& r, Vec3f v) {
  return Vec3f(float(r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z),
               float(r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z),
               float(r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z));
}

Mat3 rotationOf(const Quat& q) {
  const double x = q[0], y = q[1], z = q[2], w = q[3];
  return {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
           {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
           {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
}

double dot4(const Quat& a, const Quat& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

// Slerp along the shorter arc when b is in a's hemisphere (callers make it
// so); a normalized lerp when the two are within about 1.8 degrees.
Quat slerp(const Quat& a, const Quat& b, double t) {
  const double cosTheta = dot4(a, b);
  Quat q;
  if (cosTheta > 0.9995) {
    for (int i = 0; i < 4; ++i) q[i] = (1 - t) * a[i] + t * b[i];
    const double n = std::sqrt(dot4(q, q));
    for (double& c : q) c /= n;
    return q;
  }
  const double theta = std::acos(std::clamp(cosTheta, -1.0, 1.0));
  Quat perp;
  for (int i = 0; i < 4; ++i) perp[i] = b[i] - a[i] * cosTheta;
  const double n = std::sqrt(dot4(perp, perp));
  for (int i = 0; i < 4; ++i) q[i] = a[i] * std::cos(theta * t) + perp[i] / n * std::sin(theta * t);
  return q;
}

// pbrt's decomposition of a transform: translation, rotation and a symmetric
// stretch (polar decomposition by iteration), M = T R S.
struct Polar {
  Vec3f translation;
  Quat rotation;
  Mat3 stretch;
};

Polar polar(const Affine3f& a) {
  const Mat3 m = linearOf(a);
  Mat3 r = m;
  for (int count = 0; count < 100; ++count) {
    const Mat3 inv = inverse(r);
    Mat3 next;
    double norm = 0;
    for (int i = 0; i < 3; ++i) {
      double row = 0;
      for (int j = 0; j < 3; ++j) {
        next[i][j] = 0.5 * (r[i][j] + inv[j][i]);
        row += std::abs(r[i][j] - next[i][j]);
      }
      norm = std::max(norm, row);
    }
    r = next;
    if (norm <= 1e-4) break;
  }
  return {a.t, quaternionOf(r), multiply(inverse(r), m)};
}

bool diagonal(const Mat3& s) {
  double largest = 0, off = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double& slot = i == j ? largest : off;
      slot = std::max(slot, std::abs(s[i][j]));
    }
  return off <= 1e-6 * largest;
}

// A transform as a key: its linear part split into a rotation and an upper
// triangle (Gram-Schmidt on its columns, the rotation kept proper).
MotionKey keyOf(const Vec3f& translation, const Mat3& m, Vec3f pivot) {
  std::array<std::array<double, 3>, 3> q{};  // q[c]: column c of the rotation
  std::array<std::array<double, 3>, 3> u{};
  for (int c = 0; c < 3; ++c) {
    std::array<double, 3> v{m[0][c], m[1][c], m[2][c]};
    for (int k = 0; k < c; ++k) {
      u[k][c] = q[k][0] * v[0] + q[k][1] * v[1] + q[k][2] * v[2];
      for (int i = 0; i < 3; ++i) v[i] -= u[k][c] * q[k][i];
    }
    u[c][c] = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3; ++i) q[c][i] = v[i] / u[c][c];
  }
  Mat3 rotation;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) rotation[r][c] = q[c][r];
  if (determinant(rotation) < 0) {  // a mirror: its sign goes to the triangle
    for (int r = 0; r < 3; ++r) rotation[r][2] = -rotation[r][2];
    u[2][2] = -u[2][2];
  }
  const Quat quat = quaternionOf(rotation);
  MotionKey key;
  // About the pivot: x -> translation + R U (x - pivot) + pivot.
  key.translation = translation + pivot;
  for (int i = 0; i < 3; ++i)
    key.shift[i] = -float(u[i][0] * pivot.x + u[i][1] * pivot.y + u[i][2] * pivot.z);
  key.rotation = {float(quat[0]), float(quat[1]), float(quat[2]), float(quat[3])};
  key.scaleX = float(u[0][0]), key.skewXY = float(u[0][1]), key.skewXZ = float(u[0][2]);
  key.scaleY = float(u[1][1]), key.skewYZ = float(u[1][2]), key.scaleZ = float(u[2][2]);
  return key;
}

Quat quatOf(const MotionKey& k) {
  return {k.rotation[0], k.rotation[1], k.rotation[2], k.rotation[3]};
}

MotionKey lerpKey(const MotionKey& a, const MotionKey& b, float t) {
  auto mix = [t](float x, float y) { return (1 - t) * x + t * y; };
  MotionKey k;
  k.translation = a.translation * (1 - t) + b.translation * t;
  const Quat q = slerp(quatOf(a), quatOf(b), t);
  k.rotation = {float(q[0]), float(q[1]), float(q[2]), float(q[3])};
  k.scaleX = mix(a.scaleX, b.scaleX), k.skewXY = mix(a.skewXY, b.skewXY);
  k.skewXZ = mix(a.skewXZ, b.skewXZ), k.scaleY = mix(a.scaleY, b.scaleY);
  k.skewYZ = mix(a.skewYZ, b.skewYZ), k.scaleZ = mix(a.scaleZ, b.scaleZ);
  k.shift = a.shift * (1 - t) + b.shift * t;
  return k;
}

// Keys in one hemisphere, so each pair interpolates along the shorter arc.
void alignRotations(std::vector<MotionKey>& keys) {
  for (size_t i = 1; i < keys.size(); ++i)
    if (dot4(quatOf(keys[i - 1]), quatOf(keys[i])) < 0)
      for (float& c : keys[i].rotation) c = -c;
}

}  // namespace

Affine3f keyTransform(const MotionKey& key) {
  const Mat3 r = rotationOf(quatOf(key));
  const Mat3 u{
      {{key.scaleX, key.skewXY, key.skewXZ}, {0, key.scaleY, key.skewYZ}, {0, 0, key.scaleZ}}};
  const Mat3 m = multiply(r, u);
  Affine3f a;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a.l[i][j] = float(m[i][j]);
  a.t = key.translation + rotate(r, key.shift);
  return a;
}

// pbrt's animated transform from `start` to `end`: T, S by lerp, R by slerp
// of their decompositions.
struct PbrtMotion {
  Polar p0, p1;
  Quat r1;
  PbrtMotion(const Affine3f& start, const Affine3f& end)
      : p0(polar(start)), p1(polar(end)), r1(p1.rotation) {
    if (dot4(p0.rotation, r1) < 0)
      for (double& c : r1) c = -c;
  }
  bool sheared() const { return !diagonal(p0.stretch) || !diagonal(p1.stretch); }
  // At t: the translation and the linear part.
  std::pair<Vec3f, Mat3> at(double t) const {
    const Mat3 r = rotationOf(slerp(p0.rotation, r1, t));
    Mat3 s;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) s[i][j] = (1 - t) * p0.stretch[i][j] + t * p1.stretch[i][j];
    return {p0.translation * float(1 - t) + p1.translation * float(t), multiply(r, s)};
  }
};

// Sheared motions are sampled with this many segments.
constexpr int kShearSegments = 16;

InstanceMotion::InstanceMotion(const Affine3f& start, const Affine3f& end, Vec3f pivot) {
  // In the pivot's space: x - pivot -> M (x) - pivot.
  auto centred = [&](Affine3f m) {
    m.t = m.transformPoint(pivot) - pivot;
    return m;
  };
  const PbrtMotion motion(centred(start), centred(end));
  const int segments = motion.sheared() ? kShearSegments : 1;
  for (int k = 0; k <= segments; ++k) {
    const auto [translation, linear] = motion.at(double(k) / segments);
    keys_.push_back(keyOf(translation, linear, pivot));
  }
  alignRotations(keys_);
}

InstanceMotion InstanceMotion::nested(const Affine3f& outerStart, const Affine3f& outerEnd,
                                      const Affine3f& innerStart, const Affine3f& innerEnd,
                                      Vec3f pivot) {
  // A still outer similarity (rotation, uniform scale, translation) keeps
  // pbrt's interpolation of the products: two keys are exact.
  const Mat3 o = linearOf(outerStart);
  Mat3 gram{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) gram[i][j] += o[k][i] * o[k][j];
  bool similarity = true;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      similarity =
          similarity && std::abs(gram[i][j] - (i == j ? gram[0][0] : 0.0)) <= 1e-6 * gram[0][0];
  bool still = outerStart.t == outerEnd.t;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) still = still && outerStart.l[i][j] == outerEnd.l[i][j];
  if (still && similarity) return InstanceMotion(outerStart * innerStart, outerStart * innerEnd);
  // The outer motion in the pivot's space (x - pivot -> M (x) - pivot), so
  // x -> pivot + Lo (Li x + ti - pivot) + to.
  auto centred = [&](Affine3f m) {
    m.t = m.transformPoint(pivot) - pivot;
    return m;
  };
  const PbrtMotion outer(centred(outerStart), centred(outerEnd)), inner(innerStart, innerEnd);
  std::vector<MotionKey> keys;
  for (int k = 0; k <= kShearSegments; ++k) {
    const double t = double(k) / kShearSegments;
    const auto [to, lo] = outer.at(t);
    const auto [tInner, li] = inner.at(t);
    const Vec3f ti = tInner - pivot;
    const Vec3f translation(
        float(lo[0][0] * ti.x + lo[0][1] * ti.y + lo[0][2] * ti.z) + to.x + pivot.x,
        float(lo[1][0] * ti.x + lo[1][1] * ti.y + lo[1][2] * ti.z) + to.y + pivot.y,
        float(lo[2][0] * ti.x + lo[2][1] * ti.y + lo[2][2] * ti.z) + to.z + pivot.z);
    keys.push_back(keyOf(translation, multiply(lo, li), Vec3f(0)));
  }
  alignRotations(keys);
  return InstanceMotion(std::move(keys));
}

InstanceMotion::InstanceMotion(std::vector<MotionKey> keys) : keys_(std::move(keys)) {
  FERRY_CHECK(keys_.size() >= 2);
}

Affine3f InstanceMotion::at(float u) const {
  const size_t segments = keys_.size() - 1;
  const float x = std::clamp(u, 0.0f, 1.0f) * float(segments);
  const size_t i = std::min(size_t(x), segments - 1);
  return keyTransform(lerpKey(keys_[i], keys_[i + 1], x - float(i)));
}

Box3f InstanceMotion::sweptBox(const Box3f& box) const {
  Box3f swept;
  if (box.empty()) return swept;
  const size_t segments = keys_.size() - 1;
  const int samples = std::max(4, int(128 / segments));
  for (size_t s = 0; s < segments; ++s) {
    const MotionKey &a = keys_[s], &b = keys_[s + 1];
    // How fast a corner can move over the segment (per unit of its
    // parameter): translation, plus rotation at the largest stretched
    // radius, plus the change of stretch.
    const double angle = 2 * std::acos(std::clamp(std::abs(dot4(quatOf(a), quatOf(b))), 0.0, 1.0));
    MotionKey ra = a, rb = b;  // stretch only
    ra.rotation = rb.rotation = {0, 0, 0, 1};
    ra.translation = rb.translation = Vec3f(0);
    const Affine3f sa = keyTransform(ra), sb = keyTransform(rb);
    double speed = length(b.translation - a.translation);
    double reach = 0, change = 0;
    for (int c = 0; c < 8; ++c) {
      const Vec3f x{(c & 1) ? box.upper.x : box.lower.x, (c & 2) ? box.upper.y : box.lower.y,
                    (c & 4) ? box.upper.z : box.lower.z};
      reach =
          std::max({reach, double(length(sa.applyLinear(x))), double(length(sb.applyLinear(x)))});
      change = std::max(change, double(length(sb.applyLinear(x) - sa.applyLinear(x))));
    }
    speed += angle * reach + change;
    const float pad = float(speed / (2 * samples)) * 1.0001f + 1e-6f * float(reach);
    for (int k = 0; k <= samples; ++k) {
      Box3f pose = keyTransform(lerpKey(a, b, float(k) / float(samples))).transformBox(box);
      pose.lower = pose.lower - Vec3f(pad);
      pose.upper = pose.upper + Vec3f(pad);
      swept.extend(pose);
    }
  }
  return swept;
}

float MotionClock::u(uint32_t pixel, uint32_t sample) const {
  const uint32_t film = (pixel / imageWidth + y0) * filmWidth + pixel % imageWidth + x0;
  const RandomStream random(RandomKey{film, sample, 0, seed}, sampler);
  const float time = shutterOpen + random(RandomDim::Time) * (shutterClose - shutterOpen);
  if (!(motionEnd > motionStart)) return time <= motionStart ? 0.0f : 1.0f;
  return std::clamp((time - motionStart) / (motionEnd - motionStart), 0.0f, 1.0f);
}

}  // namespace ferry
