#include "shapes/curves.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

bool parseCurveType(std::string_view name, CurveType& type) {
  if (name == "flat")
    type = CurveType::Flat;
  else if (name == "cylinder")
    type = CurveType::Cylinder;
  else if (name == "ribbon")
    type = CurveType::Ribbon;
  else
    return false;
  return true;
}

std::string_view curveTypeName(CurveType type) {
  switch (type) {
    case CurveType::Flat:
      return "flat";
    case CurveType::Cylinder:
      return "cylinder";
    case CurveType::Ribbon:
      return "ribbon";
  }
  return "?";
}

namespace {

using Points = std::array<Vec3f, 4>;

Vec3f lerp(float t, Vec3f a, Vec3f b) {
  return a * (1 - t) + b * t;
}
float lerp(float t, float a, float b) {
  return (1 - t) * a + t * b;
}

// The cubic's blossom p(a, b, c): p(u, u, u) is the point at u, and the
// blossoms of (u0,u0,u0), (u0,u0,u1), (u0,u1,u1), (u1,u1,u1) are the control
// points of the piece [u0, u1].
Vec3f blossom(const Points& p, float a, float b, float c) {
  const Vec3f p0 = lerp(a, p[0], p[1]), p1 = lerp(a, p[1], p[2]), p2 = lerp(a, p[2], p[3]);
  const Vec3f q0 = lerp(b, p0, p1), q1 = lerp(b, p1, p2);
  return lerp(c, q0, q1);
}

// De Casteljau at t: the point, and in `derivative` dp/dt.
Vec3f evaluate(const Points& p, float t, Vec3f& derivative) {
  const Vec3f a0 = lerp(t, p[0], p[1]), a1 = lerp(t, p[1], p[2]), a2 = lerp(t, p[2], p[3]);
  const Vec3f b0 = lerp(t, a0, a1), b1 = lerp(t, a1, a2);
  const Vec3f d = b1 - b0;
  derivative = dot(d, d) > 0 ? d * 3.0f : p[3] - p[0];
  return lerp(t, b0, b1);
}

// The halves [0, 1/2] and [1/2, 1], sharing out[3].
void subdivide(const Points& p, std::array<Vec3f, 7>& out) {
  out[0] = p[0];
  out[1] = (p[0] + p[1]) * 0.5f;
  out[2] = (p[0] + p[1] * 2.0f + p[2]) * 0.25f;
  out[3] = (p[0] + p[1] * 3.0f + p[2] * 3.0f + p[3]) * 0.125f;
  out[4] = (p[1] + p[2] * 2.0f + p[3]) * 0.25f;
  out[5] = (p[2] + p[3]) * 0.5f;
  out[6] = p[3];
}

// A ribbon's normal at t between its ends' normals: spherical interpolation.
Vec3f slerpNormal(const CurveNormals& n, float t) {
  const float c = std::clamp(dot(n[0], n[1]), -1.0f, 1.0f);
  const float angle = std::acos(c);
  const float s = std::sin(angle);
  if (!(s > 1e-6f)) return normalize(lerp(t, n[0], n[1]));
  return n[0] * (std::sin((1 - t) * angle) / s) + n[1] * (std::sin(t * angle) / s);
}

// floor-ish log2 as pbrt rounds it (0 below 1).
int log2Rounded(float v) {
  if (v < 1) return 0;
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  return int(bits >> 23) - 127 + ((bits & (1u << 22)) ? 1 : 0);
}

float maxOf(float a, float b, float c, float d) {
  return std::max(std::max(a, b), std::max(c, d));
}
float minOf(float a, float b, float c, float d) {
  return std::min(std::min(a, b), std::min(c, d));
}

// One ray against one segment, in the ray's space (the ray along +z from the
// origin, z in the object's units): pbrt's recursive test, which halves the
// segment `depth` times and tests the pieces that overlap the ray as lines.
// Keeps the nearest crossing: `zMax` shrinks to it.
struct Crossing {
  const CurveSegment* segment;
  const CurveNormals* normals;  // ribbons
  Vec3f direction;              // the object-space ray direction (ribbons' width)
  float rayLength;
  float zMin;
  float zMax;
  bool found = false;
  float z = 0, u = 0, v = 0;  // u local to the segment

  float widthAt(float t) const { return lerp(t, segment->width0, segment->width1); }

  // Half h of a subdivided piece (`split`, spanning t[h] to t[h + 1]): its
  // control points; false when its box (widened by its width) misses the ray.
  bool halfMeetsRay(const std::array<Vec3f, 7>& split, const float (&t)[3], int h,
                    Points& piece) const {
    piece = {split[3 * h], split[3 * h + 1], split[3 * h + 2], split[3 * h + 3]};
    const float w = 0.5f * std::max(widthAt(t[h]), widthAt(t[h + 1]));
    if (maxOf(piece[0].y, piece[1].y, piece[2].y, piece[3].y) + w < 0 ||
        minOf(piece[0].y, piece[1].y, piece[2].y, piece[3].y) - w > 0)
      return false;
    if (maxOf(piece[0].x, piece[1].x, piece[2].x, piece[3].x) + w < 0 ||
        minOf(piece[0].x, piece[1].x, piece[2].x, piece[3].x) - w > 0)
      return false;
    return !(maxOf(piece[0].z, piece[1].z, piece[2].z, piece[3].z) + w < zMin ||
             minOf(piece[0].z, piece[1].z, piece[2].z, piece[3].z) - w > zMax);
  }

  // test() over the leaves that overlap (lo, hi) only: the same halvings,
  // so the same leaves (a leaf across lo or hi is tested by both pieces,
  // which then find the same crossing).
  void testRange(const Points& cp, float t0, float t1, int depth, float lo, float hi) {
    if (depth == 0 || (t0 >= lo && t1 <= hi)) return test(cp, t0, t1, depth);
    std::array<Vec3f, 7> split;
    subdivide(cp, split);
    const float t[3] = {t0, (t0 + t1) * 0.5f, t1};
    Points piece;
    for (int h = 0; h < 2; ++h)
      if (t[h + 1] > lo && t[h] < hi && halfMeetsRay(split, t, h, piece))
        testRange(piece, t[h], t[h + 1], depth - 1, lo, hi);
  }

  void test(const Points& cp, float t0, float t1, int depth) {
    if (depth > 0) {
      std::array<Vec3f, 7> split;
      subdivide(cp, split);
      const float t[3] = {t0, (t0 + t1) * 0.5f, t1};
      Points piece;
      for (int h = 0; h < 2; ++h)
        if (halfMeetsRay(split, t, h, piece)) test(piece, t[h], t[h + 1], depth - 1);
      return;
    }
    // The ray must pass between the planes perpendicular to the curve at
    // its two ends.
    if ((cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x) < 0) return;
    if ((cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x) < 0) return;
    // The nearest point to the ray on the piece taken as a line.
    const Vec2f along{cp[3].x - cp[0].x, cp[3].y - cp[0].y};
    const float denominator = along.x * along.x + along.y * along.y;
    if (denominator == 0) return;
    const float w = (-cp[0].x * along.x - cp[0].y * along.y) / denominator;
    const float t = std::clamp(lerp(w, t0, t1), t0, t1);
    float width = widthAt(t);
    if (normals) width *= std::abs(dot(slerpNormal(*normals, t), direction)) / rayLength;
    Vec3f tangent;
    const Vec3f p = evaluate(cp, std::clamp(w, 0.0f, 1.0f), tangent);
    const float distance2 = p.x * p.x + p.y * p.y;
    if (!(distance2 <= width * width * 0.25f) || !(width > 0)) return;
    if (!(p.z > zMin) || !(p.z < zMax)) return;
    const float distance = std::sqrt(distance2);
    const float side = tangent.x * -p.y + p.x * tangent.y;
    found = true;
    z = zMax = p.z;
    u = t;
    v = side > 0 ? 0.5f + distance / width : 0.5f - distance / width;
  }
};

void checkFinite(Vec3f p, size_t segment, const char* what) {
  if (!isFinite(p))
    throw InputError(fmt::format("curves: segment {} has a {} ({}, {}, {}) that is not finite",
                                 segment, what, p.x, p.y, p.z));
}

}  // namespace

void appendCurveSegments(const Points& points, float width0, float width1,
                         const CurveNormals* normals, int splitDepth,
                         std::vector<CurveSegment>& out, std::vector<CurveNormals>* normalsOut) {
  const int pieces = 1 << std::clamp(splitDepth, 0, 20);
  for (int k = 0; k < pieces; ++k) {
    const float u0 = float(k) / float(pieces), u1 = float(k + 1) / float(pieces);
    CurveSegment s;
    s.points = {blossom(points, u0, u0, u0), blossom(points, u0, u0, u1),
                blossom(points, u0, u1, u1), blossom(points, u1, u1, u1)};
    s.width0 = lerp(u0, width0, width1);
    s.width1 = lerp(u1, width0, width1);
    s.u0 = u0;
    s.u1 = u1;
    out.push_back(s);
    if (normals && normalsOut) {
      const CurveNormals n{normalize((*normals)[0]), normalize((*normals)[1])};
      normalsOut->push_back({slerpNormal(n, u0), slerpNormal(n, u1)});
    }
  }
}

Curves::Curves(CurveType type, std::vector<CurveSegment> segments,
               std::vector<CurveNormals> normals)
    : type_(type),
      pieces_(traversalPiecesFor(type, segments.size())),
      segments_(std::move(segments)),
      normals_(std::move(normals)) {
  if (segments_.size() > UINT32_MAX)
    throw InputError(fmt::format("curves: {} segments is more than 2^32 - 1", segments_.size()));
  if (type_ == CurveType::Ribbon && normals_.size() != segments_.size())
    throw InputError(fmt::format("curves: {} ribbon segments but {} normal pairs", segments_.size(),
                                 normals_.size()));
  if (type_ != CurveType::Ribbon && !normals_.empty())
    throw InputError(fmt::format("curves: normals given for {} curves", curveTypeName(type_)));
  for (size_t k = 0; k < segments_.size(); ++k) {
    const CurveSegment& s = segments_[k];
    for (const Vec3f& p : s.points) checkFinite(p, k, "control point");
    if (!(s.width0 >= 0) || !(s.width1 >= 0) || !std::isfinite(s.width0) ||
        !std::isfinite(s.width1) || !(s.width0 + s.width1 > 0))
      throw InputError(
          fmt::format("curves: segment {} has widths {} and {}", k, s.width0, s.width1));
    if (!std::isfinite(s.u0) || !std::isfinite(s.u1))
      throw InputError(fmt::format("curves: segment {} has u {} to {}", k, s.u0, s.u1));
  }
  for (size_t k = 0; k < normals_.size(); ++k)
    for (Vec3f& n : normals_[k]) {
      checkFinite(n, k, "normal");
      const float len = length(n);
      if (!(len > 0)) throw InputError(fmt::format("curves: segment {} has a zero normal", k));
      n = n * (1 / len);
    }
  if (type_ == CurveType::Ribbon) return;
  if (segments_.size() > UINT32_MAX / 4)
    throw InputError(fmt::format("curves: {} flat segments is more than 2^30, Embree's index",
                                 segments_.size()));
  // The radius along a segment is linear: its cubic control values are the
  // line's, raised to degree 3.
  points_.resize(4 * segments_.size());
  first_.resize(segments_.size());
  for (size_t k = 0; k < segments_.size(); ++k) {
    const CurveSegment& s = segments_[k];
    const float r[4] = {0.5f * s.width0, (2 * s.width0 + s.width1) / 6,
                        (s.width0 + 2 * s.width1) / 6, 0.5f * s.width1};
    for (int j = 0; j < 4; ++j)
      points_[4 * k + size_t(j)] = {s.points[j].x, s.points[j].y, s.points[j].z, r[j]};
    first_[k] = uint32_t(4 * k);
  }
}

Box3f Curves::primitiveBounds(uint32_t primitive) const {
  const CurveSegment& s = segments_[primitive];
  Box3f b;
  for (const Vec3f& p : s.points) b.extend(p);
  const float r = 0.5f * std::max(s.width0, s.width1);
  return {b.lower - Vec3f(r), b.upper + Vec3f(r)};
}

uint64_t Curves::bytes() const {
  return segments_.capacity() * sizeof(CurveSegment) + normals_.capacity() * sizeof(CurveNormals) +
         points_.capacity() * sizeof(Vec4f) + first_.capacity() * sizeof(uint32_t);
}

uint64_t Curves::bytesPerSegment(CurveType type) {
  return sizeof(CurveSegment) +
         (type == CurveType::Ribbon ? sizeof(CurveNormals) : 4 * sizeof(Vec4f) + sizeof(uint32_t));
}

uint32_t Curves::traversalPiecesFor(CurveType type, uint64_t segments) {
  if (type != CurveType::Ribbon) return 1;
  return segments <= UINT32_MAX / kTraversalPieces ? kTraversalPieces : 1;
}

Shape::FlatCurves Curves::flatCurves() const {
  if (type_ == CurveType::Ribbon) return {};
  return {points_, first_, kTessellation};
}

Box3f Curves::pieceBounds(uint32_t primitive, uint32_t piece) const {
  const CurveSegment& s = segments_[primitive];
  const float u0 = float(piece) / float(pieces_), u1 = float(piece + 1) / float(pieces_);
  Box3f b;
  for (const Vec3f& p : {blossom(s.points, u0, u0, u0), blossom(s.points, u0, u0, u1),
                         blossom(s.points, u0, u1, u1), blossom(s.points, u1, u1, u1)})
    b.extend(p);
  // Half the piece's width, and a margin for the crossing's rounding.
  const float scale = std::max(maxComponent(b.size()), maxComponent(max(-b.lower, b.upper)));
  const float r =
      0.5f * std::max(lerp(u0, s.width0, s.width1), lerp(u1, s.width0, s.width1)) + 1e-5f * scale;
  return {b.lower - Vec3f(r), b.upper + Vec3f(r)};
}

bool Curves::intersect(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                       float& t, Vec2f& uv) const {
  if (type_ != CurveType::Ribbon)
    return crossFlat(primitive, origin, direction, tnear, tfar, t, uv);
  return crossPiece(primitive, 0, 1, origin, direction, tnear, tfar, t, uv);
}

bool Curves::intersectPiece(uint32_t primitive, uint32_t piece, Vec3f origin, Vec3f direction,
                            float tnear, float tfar, float& t, Vec2f& uv, ShapeWork&) const {
  if (type_ != CurveType::Ribbon)
    return crossFlat(primitive, origin, direction, tnear, tfar, t, uv);
  return crossPiece(primitive, piece, pieces_, origin, direction, tnear, tfar, t, uv);
}

namespace {

// The quad a, b, c, d (a to b along the curve, a to d across) against the
// ray from the origin along +z, as two triangles split by b-d; Embree's
// test, which accepts the quad seen from one side only: false, or its t and
// (u, v) across the quad.
bool crossQuad(Vec3f a, Vec3f b, Vec3f c, Vec3f d, float tnear, float tfar, float& t, float& u,
               float& v) {
  const auto crossZ = [](Vec3f p, Vec3f q) { return p.x * q.y - p.y * q.x; };
  const float ww = crossZ(d, b - d);
  const bool first = ww <= 0;
  const Vec3f v0 = first ? a : c, v1 = first ? b : d, v2 = first ? d : b;
  const Vec3f e0 = v2 - v0, e1 = v0 - v1;
  const float uu = crossZ(v0, e0), vv = crossZ(v1, e1);
  if (!(std::max(uu, vv) <= 0)) return false;
  const Vec3f ng = cross(e1, e0);
  const float den = ng.z;
  if (den == 0) return false;
  t = dot(v0, ng) / den;
  if (!(tnear <= t && t <= tfar)) return false;
  u = uu / den;
  v = vv / den;
  if (!first) {
    u = 1 - u;
    v = 1 - v;
  }
  return true;
}

// Embree's self-intersection avoidance for flat curves (its build's
// EMBREE_CURVE_SELF_INTERSECTION_AVOIDANCE_FACTOR, 2 in Debian's): a crossing
// nearer the ray's origin than this many radii is not one.
constexpr float kSelfAvoidance = 2.0f;

}  // namespace

// Embree's rule for its flat Bézier curves: in the ray's space (z along the
// ray, in units of t), the curve is cut into kTessellation straight pieces;
// each is a quad its radius wide on either side, across the piece's ends'
// tangents as the ray sees them; the nearest quad crossed wins.
bool Curves::crossFlat(uint32_t primitive, Vec3f origin, Vec3f direction, float tnear, float tfar,
                       float& t, Vec2f& uv) const {
  const float dd = dot(direction, direction);
  if (!(dd > 0)) return false;
  const float depthScale = 1 / std::sqrt(dd);
  const Vec3f n = direction * depthScale;
  const Vec3f dx0(0, n.z, -n.y), dx1(-n.z, 0, n.x);
  const Vec3f dx = normalize(dot(dx0, dx0) > dot(dx1, dx1) ? dx0 : dx1);
  const Vec3f dy = normalize(cross(n, dx));
  const Vec3f dz = n * depthScale;
  Points q;
  float largest = 0;
  for (int k = 0; k < 4; ++k) {
    const Vec4f& p = points_[4 * size_t(primitive) + size_t(k)];
    const Vec3f r = p.xyz() - origin;
    q[k] = {dot(r, dx), dot(r, dy), dot(r, dz)};
    largest = std::max({largest, maxComponent(max(q[k], -q[k])), p.w});
  }
  const float eps = 4 * std::numeric_limits<float>::epsilon() * largest;
  // The radius is linear along the segment (its control values are the
  // line's raised to degree 3).
  const float r0 = points_[4 * size_t(primitive)].w, r3 = points_[4 * size_t(primitive) + 3].w;
  // The unit direction across the curve as the ray sees it (the tangent
  // turned a right angle in the ray's plane); a vanishing tangent is taken
  // from the piece's chord.
  const auto across = [&](Vec3f d, Vec3f chord) {
    if (maxComponent(max(d, -d)) < eps) d = chord;
    return normalize(Vec3f(d.y, -d.x, 0));
  };
  bool found = false;
  float bestT = kInfinity, bestU = 0, bestV = 0;
  constexpr float kStep = 1.0f / kTessellation;
  for (int i = 0; i < kTessellation; ++i) {
    const float u0 = float(i) * kStep, u1 = float(i + 1) * kStep;
    Vec3f d0, d1;
    const Vec3f c0 = evaluate(q, u0, d0), c1 = evaluate(q, u1, d1);
    const float w0 = lerp(u0, r0, r3), w1 = lerp(u1, r0, r3);
    // Cull: the ray must pass within the larger radius of the piece's line.
    const float ax = c1.x - c0.x, ay = c1.y - c0.y;
    const float num = ax * c0.y - ay * c0.x;
    const float r = std::max(w0, w1);
    if (!(num * num <= r * r * (ax * ax + ay * ay))) continue;
    const Vec3f n0 = across(d0, c1 - c0), n1 = across(d1, c1 - c0);
    float ti, ui, vi;
    if (!crossQuad(c0 + n0 * w0, c1 + n1 * w1, c1 - n1 * w1, c0 - n0 * w0, tnear, tfar, ti, ui, vi))
      continue;
    const float radius = lerp(ui, w0, w1);
    if (!(ti > kSelfAvoidance * radius * depthScale)) continue;
    if (found && !(ti < bestT)) continue;
    found = true;
    bestT = ti;
    bestU = (float(i) + ui) * kStep;
    bestV = 2 * vi - 1;
  }
  if (!found || !(bestT > tnear && bestT < tfar)) return false;
  t = bestT;
  uv = {bestU, bestV};
  return true;
}

bool Curves::crossPiece(uint32_t primitive, uint32_t piece, uint32_t pieces, Vec3f origin,
                        Vec3f direction, float tnear, float tfar, float& t, Vec2f& uv) const {
  const CurveSegment& s = segments_[primitive];
  const float rayLength = length(direction);
  if (!(rayLength > 0)) return false;
  // The ray's space: z along the ray, y perpendicular to it and to the
  // segment's chord (any perpendicular when they are parallel).
  const Vec3f dir = direction * (1 / rayLength);
  Vec3f up = cross(direction, s.points[3] - s.points[0]);
  if (!(dot(up, up) > 0)) up = Frame(dir).s;
  const Vec3f right = normalize(cross(normalize(up), dir));
  const Vec3f newUp = cross(dir, right);
  Points cp;
  for (int k = 0; k < 4; ++k) {
    const Vec3f q = s.points[k] - origin;
    cp[k] = {dot(q, right), dot(q, newUp), dot(q, dir)};
  }
  const float zMin = tnear * rayLength;
  const float zMax = std::min(tfar * rayLength, std::numeric_limits<float>::max());
  // The segment's box against the ray's.
  const float w = 0.5f * std::max(s.width0, s.width1);
  if (maxOf(cp[0].x, cp[1].x, cp[2].x, cp[3].x) + w < 0 ||
      minOf(cp[0].x, cp[1].x, cp[2].x, cp[3].x) - w > 0 ||
      maxOf(cp[0].y, cp[1].y, cp[2].y, cp[3].y) + w < 0 ||
      minOf(cp[0].y, cp[1].y, cp[2].y, cp[3].y) - w > 0 ||
      maxOf(cp[0].z, cp[1].z, cp[2].z, cp[3].z) + w < zMin ||
      minOf(cp[0].z, cp[1].z, cp[2].z, cp[3].z) - w > zMax)
    return false;
  // pbrt's refinement depth: enough halvings that each piece is straight to
  // within a twentieth of the width.
  float l0 = 0;
  for (int i = 0; i < 2; ++i)
    for (int c = 0; c < 3; ++c)
      l0 = std::max(l0, std::abs(cp[i][c] - 2 * cp[i + 1][c] + cp[i + 2][c]));
  const float eps = std::max(s.width0, s.width1) * 0.05f;
  const int depth = std::clamp(log2Rounded(1.41421356237f * 6.0f * l0 / (8.0f * eps)) / 2, 0, 10);
  Crossing crossing{&s,        type_ == CurveType::Ribbon ? &normals_[primitive] : nullptr,
                    direction, rayLength,
                    zMin,      zMax};
  crossing.testRange(cp, 0, 1, depth, float(piece) / float(pieces),
                     float(piece + 1) / float(pieces));
  if (!crossing.found) return false;
  t = crossing.z / rayLength;
  if (!(t > tnear && t < tfar)) return false;
  uv = {crossing.u, 2 * crossing.v - 1};
  return true;
}

ShapeSurface Curves::surface(uint32_t primitive, Vec2f uv) const {
  // No ray: seen from a direction perpendicular to the tangent.
  const CurveSegment& s = segments_[primitive];
  Vec3f tangent;
  evaluate(s.points, 0.5f, tangent);
  const Vec3f axis = dot(tangent, tangent) > 0 ? normalize(tangent) : Vec3f(0, 0, 1);
  return surface(primitive, uv, Frame(axis).s);
}

ShapeSurface Curves::surface(uint32_t primitive, Vec2f uv, Vec3f direction) const {
  const CurveSegment& s = segments_[primitive];
  const float span = s.u1 - s.u0;
  const float t = std::clamp(uv.x, 0.0f, 1.0f);
  const float across = std::clamp(0.5f * (uv.y + 1), 0.0f, 1.0f);  // 0 to 1
  Vec3f derivative;
  const Vec3f p = evaluate(s.points, t, derivative);
  const Vec3f dpdu = span != 0 ? derivative * (1 / span) : derivative;
  const float width = lerp(t, s.width0, s.width1);
  const float dirLength = length(direction);
  const Vec3f d = dirLength > 0 ? direction * (1 / dirLength) : Frame(normalize(dpdu)).s;
  Vec3f side, dpdv;
  if (type_ == CurveType::Ribbon) {
    const Vec3f n = slerpNormal(normals_[primitive], t);
    side = normalize(cross(n, dpdu));
    dpdv = side * (width * std::abs(dot(n, d)));
    // v runs across the ribbon as the ray sees it (as for flat curves): the
    // side that looks like cross(d, dp/du).
    if (dot(side, cross(d, dpdu)) < 0) side = -side;
  } else {
    // Facing the ray: across the ray and the tangent.
    side = cross(d, dpdu);
    const float len = length(side);
    side = len > 0 ? side * (1 / len) : Frame(d).s;
    dpdv = side * width;
    if (type_ == CurveType::Cylinder) {
      // Turned about the tangent, -90 to 90 degrees across the width: shaded as a tube.
      const float theta = lerp(across, -0.5f * kPi, 0.5f * kPi);
      dpdv = Affine3f::rotate(dpdu, -theta).transformVector(dpdv);
    }
  }
  Vec3f n = cross(dpdu, dpdv);
  const float len = length(n);
  n = len > 0 && std::isfinite(len) ? n * (1 / len) : -d;
  ShapeSurface out;
  out.position = p + side * ((across - 0.5f) * width);
  out.geometricNormal = n;
  out.shadingNormal = n;
  out.uv = {lerp(t, s.u0, s.u1), across};
  out.tangent = dpdu;
  out.originOffset = 2 * width;
  return out;
}

std::shared_ptr<const Shape> Curves::subset(std::span<const uint32_t> primitives) const {
  std::vector<CurveSegment> segments;
  std::vector<CurveNormals> normals;
  segments.reserve(primitives.size());
  for (uint32_t p : primitives) {
    segments.push_back(segments_.at(p));
    if (type_ == CurveType::Ribbon) normals.push_back(normals_[p]);
  }
  return std::make_shared<Curves>(type_, std::move(segments), std::move(normals));
}

void Curves::write(RecordWriter& record) const {
  record.pod(uint8_t(type_));
  record.array<CurveSegment>(segments_);
  record.array<CurveNormals>(normals_);
}

std::shared_ptr<const Shape> Curves::read(RecordReader& record) {
  const auto type = record.pod<uint8_t>();
  if (type > uint8_t(CurveType::Ribbon)) record.fail(fmt::format("curves: unknown type {}", type));
  std::vector<CurveSegment> segments = record.array<CurveSegment>();
  std::vector<CurveNormals> normals = record.array<CurveNormals>();
  try {
    return std::make_shared<Curves>(CurveType(type), std::move(segments), std::move(normals));
  } catch (const InputError& e) {
    record.fail(e.what());
  }
}

std::string Curves::describe() const {
  return fmt::format("{} {} curve segments", segments_.size(), curveTypeName(type_));
}

}  // namespace ferry
