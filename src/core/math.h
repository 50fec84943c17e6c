// Small value types for geometry: vectors, boxes and affine transforms.
// Plain structs with inline operators so they cost nothing in hot loops and can
// be copied into MPI buffers and part files as they are.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace ferry {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

struct Vec2f {
  float x = 0, y = 0;
  Vec2f() = default;
  constexpr Vec2f(float x_, float y_) : x(x_), y(y_) {}
  float operator[](int i) const { return (&x)[i]; }
  float& operator[](int i) { return (&x)[i]; }
};
inline Vec2f operator+(Vec2f a, Vec2f b) {
  return {a.x + b.x, a.y + b.y};
}
inline Vec2f operator-(Vec2f a, Vec2f b) {
  return {a.x - b.x, a.y - b.y};
}
inline Vec2f operator*(Vec2f a, float s) {
  return {a.x * s, a.y * s};
}
inline Vec2f operator*(float s, Vec2f a) {
  return {a.x * s, a.y * s};
}

struct Vec3f {
  float x = 0, y = 0, z = 0;
  Vec3f() = default;
  constexpr Vec3f(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  constexpr explicit Vec3f(float s) : x(s), y(s), z(s) {}
  float operator[](int i) const { return (&x)[i]; }
  float& operator[](int i) { return (&x)[i]; }
};
inline Vec3f operator+(Vec3f a, Vec3f b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3f operator-(Vec3f a, Vec3f b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3f operator-(Vec3f a) {
  return {-a.x, -a.y, -a.z};
}
inline Vec3f operator*(Vec3f a, Vec3f b) {
  return {a.x * b.x, a.y * b.y, a.z * b.z};
}
inline Vec3f operator*(Vec3f a, float s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline Vec3f operator*(float s, Vec3f a) {
  return {a.x * s, a.y * s, a.z * s};
}
inline Vec3f operator/(Vec3f a, float s) {
  return a * (1.0f / s);
}
inline Vec3f operator/(Vec3f a, Vec3f b) {
  return {a.x / b.x, a.y / b.y, a.z / b.z};
}
inline Vec3f& operator+=(Vec3f& a, Vec3f b) {
  return a = a + b;
}
inline Vec3f& operator-=(Vec3f& a, Vec3f b) {
  return a = a - b;
}
inline Vec3f& operator*=(Vec3f& a, Vec3f b) {
  return a = a * b;
}
inline Vec3f& operator*=(Vec3f& a, float s) {
  return a = a * s;
}
inline bool operator==(Vec3f a, Vec3f b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}
inline float dot(Vec3f a, Vec3f b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3f cross(Vec3f a, Vec3f b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3f a) {
  return std::sqrt(dot(a, a));
}
inline Vec3f normalize(Vec3f a) {
  return a * (1.0f / length(a));
}

// sin and cos of the angle 2 pi u, for u in [0, 1] (the azimuth of every
// direction sampler). The quarter turn is taken from u exactly (u * 4 and its
// rounding lose nothing), the rest is at most an eighth of a turn, where
// minimax polynomials of degree 7 (sin) and 6 (cos) are within 2e-7 of the
// true values (math_test.cpp). No branches: the quadrant is random, so a
// branch on it would be mispredicted every other time (docs/performance.md).
inline void sinCosTwoPi(float u, float& sinOut, float& cosOut) {
  const float quarters = u * 4.0f;
  const uint32_t k = uint32_t(quarters + 0.5f);       // nearest quarter turn, 0..4
  const float a = (quarters - float(k)) * (kPi / 2);  // |a| <= pi / 4
  const float a2 = a * a;
  const float s = a + a * a2 *
                          (-0.16666637361049652f +
                           a2 * (0.008331584744155407f + a2 * -0.00019462115596979856f));
  const float c =
      1 + a2 * (-0.4999985694885254f + a2 * (0.041655026376247406f + a2 * -0.0013585907872766256f));
  // Rotate (c, s) by k quarter turns: swap on odd k, then the signs, in bits.
  const uint32_t swap = 0u - (k & 1u);
  const uint32_t sBits = std::bit_cast<uint32_t>(s), cBits = std::bit_cast<uint32_t>(c);
  const uint32_t sinBits = ((sBits & ~swap) | (cBits & swap)) ^ ((k & 2u) << 30);
  const uint32_t cosBits = ((cBits & ~swap) | (sBits & swap)) ^ (((k + 1u) & 2u) << 30);
  sinOut = std::bit_cast<float>(sinBits);
  cosOut = std::bit_cast<float>(cosBits);
}
inline Vec3f min(Vec3f a, Vec3f b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3f max(Vec3f a, Vec3f b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline float maxComponent(Vec3f a) {
  return std::max(a.x, std::max(a.y, a.z));
}
inline float minComponent(Vec3f a) {
  return std::min(a.x, std::min(a.y, a.z));
}
inline float luminance(Vec3f c) {
  return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}
inline bool isFinite(Vec3f a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline Vec3f lerp(Vec3f a, Vec3f b, float t) {
  return a * (1 - t) + b * t;
}

struct Vec3i {
  int32_t x = 0, y = 0, z = 0;
  int32_t operator[](int i) const { return (&x)[i]; }
};

struct Vec4f {
  float x = 0, y = 0, z = 0, w = 0;
  Vec3f xyz() const { return {x, y, z}; }
};

// Axis-aligned box; empty when lower > upper.
struct Box3f {
  Vec3f lower{kInfinity};
  Vec3f upper{-kInfinity};

  bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
  void extend(Vec3f p) {
    lower = min(lower, p);
    upper = max(upper, p);
  }
  void extend(const Box3f& b) {
    lower = min(lower, b.lower);
    upper = max(upper, b.upper);
  }
  Vec3f size() const { return upper - lower; }
  Vec3f center() const { return (lower + upper) * 0.5f; }
  float surfaceArea() const {
    if (empty()) return 0;
    Vec3f d = size();
    return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
  }
  int longestAxis() const {
    Vec3f d = size();
    return d.x >= d.y && d.x >= d.z ? 0 : (d.y >= d.z ? 1 : 2);
  }
  bool contains(const Box3f& b) const {
    return b.lower.x >= lower.x && b.lower.y >= lower.y && b.lower.z >= lower.z &&
           b.upper.x <= upper.x && b.upper.y <= upper.y && b.upper.z <= upper.z;
  }
  bool overlaps(const Box3f& b) const {
    return !(b.lower.x > upper.x || b.lower.y > upper.y || b.lower.z > upper.z ||
             b.upper.x < lower.x || b.upper.y < lower.y || b.upper.z < lower.z);
  }
  // The slab test: narrows [t0, t1] to where origin + t direction lies in
  // the box (touching counts), `inverse` being 1 / direction per axis;
  // false, leaving t0 > t1, when nothing is left. A NaN (0 * inf: the origin
  // on a slab plane of a zero direction) counts as inside that slab. Inline:
  // the proxy query runs it for every node and leaf box it meets.
  [[gnu::always_inline]] bool clipRay(Vec3f origin, Vec3f inverse, float& t0, float& t1) const {
    for (int a = 0; a < 3; ++a) {
      float lo = (lower[a] - origin[a]) * inverse[a];
      float hi = (upper[a] - origin[a]) * inverse[a];
      if (lo > hi) std::swap(lo, hi);
      if (!(lo <= hi)) continue;
      t0 = std::max(t0, lo);
      t1 = std::min(t1, hi);
      if (t0 > t1) return false;
    }
    return true;
  }
};

// Row-major 3x3 linear part plus translation: p' = L * p + t.
struct Affine3f {
  float l[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3f t{0, 0, 0};

  static Affine3f identity() { return {}; }
  bool isIdentity() const {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        if (l[r][c] != (r == c ? 1.0f : 0.0f)) return false;
    return t == Vec3f(0, 0, 0);
  }
  static Affine3f translate(Vec3f d) {
    Affine3f a;
    a.t = d;
    return a;
  }
  static Affine3f scale(Vec3f s) {
    Affine3f a;
    a.l[0][0] = s.x;
    a.l[1][1] = s.y;
    a.l[2][2] = s.z;
    return a;
  }
  // Rotation by `radians` around the unit `axis` (right-handed).
  static Affine3f rotate(Vec3f axis, float radians) {
    Vec3f u = normalize(axis);
    float c = std::cos(radians), s = std::sin(radians), C = 1 - c;
    Affine3f a;
    a.l[0][0] = c + u.x * u.x * C;
    a.l[0][1] = u.x * u.y * C - u.z * s;
    a.l[0][2] = u.x * u.z * C + u.y * s;
    a.l[1][0] = u.y * u.x * C + u.z * s;
    a.l[1][1] = c + u.y * u.y * C;
    a.l[1][2] = u.y * u.z * C - u.x * s;
    a.l[2][0] = u.z * u.x * C - u.y * s;
    a.l[2][1] = u.z * u.y * C + u.x * s;
    a.l[2][2] = c + u.z * u.z * C;
    return a;
  }

  Vec3f applyLinear(Vec3f v) const {
    return {l[0][0] * v.x + l[0][1] * v.y + l[0][2] * v.z,
            l[1][0] * v.x + l[1][1] * v.y + l[1][2] * v.z,
            l[2][0] * v.x + l[2][1] * v.y + l[2][2] * v.z};
  }
  Vec3f transformPoint(Vec3f p) const { return applyLinear(p) + t; }
  Vec3f transformVector(Vec3f v) const { return applyLinear(v); }
  // Normals transform by the inverse transpose.
  Vec3f transformNormal(Vec3f n) const {
    Affine3f inv = inverse();
    return {inv.l[0][0] * n.x + inv.l[1][0] * n.y + inv.l[2][0] * n.z,
            inv.l[0][1] * n.x + inv.l[1][1] * n.y + inv.l[2][1] * n.z,
            inv.l[0][2] * n.x + inv.l[1][2] * n.y + inv.l[2][2] * n.z};
  }
  float determinant() const {
    return l[0][0] * (l[1][1] * l[2][2] - l[1][2] * l[2][1]) -
           l[0][1] * (l[1][0] * l[2][2] - l[1][2] * l[2][0]) +
           l[0][2] * (l[1][0] * l[2][1] - l[1][1] * l[2][0]);
  }
  Affine3f inverse() const {
    Affine3f r;
    float invDet = 1.0f / determinant();
    r.l[0][0] = (l[1][1] * l[2][2] - l[1][2] * l[2][1]) * invDet;
    r.l[0][1] = (l[0][2] * l[2][1] - l[0][1] * l[2][2]) * invDet;
    r.l[0][2] = (l[0][1] * l[1][2] - l[0][2] * l[1][1]) * invDet;
    r.l[1][0] = (l[1][2] * l[2][0] - l[1][0] * l[2][2]) * invDet;
    r.l[1][1] = (l[0][0] * l[2][2] - l[0][2] * l[2][0]) * invDet;
    r.l[1][2] = (l[0][2] * l[1][0] - l[0][0] * l[1][2]) * invDet;
    r.l[2][0] = (l[1][0] * l[2][1] - l[1][1] * l[2][0]) * invDet;
    r.l[2][1] = (l[0][1] * l[2][0] - l[0][0] * l[2][1]) * invDet;
    r.l[2][2] = (l[0][0] * l[1][1] - l[0][1] * l[1][0]) * invDet;
    r.t = -r.applyLinear(t);
    return r;
  }
  Box3f transformBox(const Box3f& b) const {
    Box3f r;
    if (b.empty()) return r;
    for (int i = 0; i < 8; ++i) {
      Vec3f c{(i & 1) ? b.upper.x : b.lower.x, (i & 2) ? b.upper.y : b.lower.y,
              (i & 4) ? b.upper.z : b.lower.z};
      r.extend(transformPoint(c));
    }
    return r;
  }
};

// a * b: apply b first, then a.
inline Affine3f operator*(const Affine3f& a, const Affine3f& b) {
  Affine3f r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r.l[i][j] = a.l[i][0] * b.l[0][j] + a.l[i][1] * b.l[1][j] + a.l[i][2] * b.l[2][j];
  r.t = a.applyLinear(b.t) + a.t;
  return r;
}

// Orthonormal basis around a unit normal (Duff et al. 2017), for local shading frames.
struct Frame {
  Vec3f s, t, n;
  // (Always inlined: a handful of multiplies each, called at every vertex;
  // GCC may otherwise leave toLocal out of line.)
  [[gnu::always_inline]] explicit Frame(Vec3f normal) : n(normal) {
    float sign = std::copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    s = {1 + sign * n.x * n.x * a, sign * b, -sign * n.x};
    t = {b, sign + n.y * n.y * a, -n.y};
  }
  // About `normal` with s along `tangent` made perpendicular to it (any
  // perpendicular when the tangent is parallel to the normal or zero).
  Frame(Vec3f normal, Vec3f tangent) : Frame(normal) {
    const Vec3f along = tangent - n * dot(n, tangent);
    const float len = std::sqrt(dot(along, along));
    if (!(len > 1e-12f) || !std::isfinite(len)) return;
    s = along * (1 / len);
    t = cross(n, s);
  }
  [[gnu::always_inline]] Vec3f toLocal(Vec3f v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
  [[gnu::always_inline]] Vec3f toWorld(Vec3f v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace ferry
