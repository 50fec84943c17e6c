#include "render/lights.h"

#include <cmath>

#include "render/bsdf.h"

namespace ferry {
namespace {

// Up to this many emissive triangles are candidates one by one; more are
// grouped, so a light sample stays cheap however many emitters a scene has.
constexpr size_t kMaxIndividualTriangles = 64;
constexpr size_t kTrianglesPerGroup = 256;

Vec3f sunRadiance(const SunLight& sun) {
  float s = std::sin(sun.angularRadius);
  return sun.irradiance * (1.0f / (kPi * s * s));
}

// 1 - cos(r) without cancellation: in float, 1 - cos(0.00465) is off by 0.2%
// (and by 1.3% at r = 0.002), which biased every sunlit pixel by as much.
float oneMinusCos(float r) {
  float s = std::sin(0.5f * r);
  return 2 * s * s;
}

float sunConePdf(const SunLight& sun) {
  return 1.0f / (2 * kPi * oneMinusCos(sun.angularRadius));
}

}  // namespace

LightSampler::LightSampler(const Scene& scene)
    : suns_(scene.suns), environment_(scene.environment) {
  for (const SunLight& sun : suns_)
    sunConstants_.push_back({sunRadiance(sun), sunConePdf(sun), oneMinusCos(sun.angularRadius),
                             2 * std::sin(0.5f * sun.angularRadius), luminance(sun.irradiance),
                             Frame(sun.direction)});
  if (environment_.image) {
    const HdrImage& img = *environment_.image;
    std::vector<float> weights(size_t(img.width) * img.height);
    double sum = 0;
    for (int y = 0; y < img.height; ++y) {
      float sinTheta = std::sin(kPi * (y + 0.5f) / img.height);
      for (int x = 0; x < img.width; ++x) {
        float l = luminance(img.at(x, y) * environment_.color);
        weights[size_t(y) * img.width + x] = l * sinTheta;
        sum += l * sinTheta;
      }
    }
    environmentDistribution_ = Distribution2D(weights, img.width, img.height);
    // Average radiance over the sphere: sum(L sin) * dtheta dphi / 4pi.
    environmentWeight_ = float(sum * (kPi / img.height) * (2 * kPi / img.width) / (4 * kPi)) * kPi;
  } else {
    environmentWeight_ = luminance(environment_.color) * kPi;
  }

  // Emissive triangles in world space, from every instance of every emissive mesh.
  std::vector<std::vector<int32_t>> emissiveMeshesPerObject(scene.objects.size());
  for (size_t o = 0; o < scene.objects.size(); ++o)
    for (int32_t m : scene.objects[o].meshes)
      if (scene.materials[scene.meshes[m].material].isEmissive())
        emissiveMeshesPerObject[o].push_back(m);
  for (const Instance& inst : scene.instances) {
    for (int32_t m : emissiveMeshesPerObject[inst.object]) {
      const Mesh& mesh = scene.meshes[m];
      const Material& material = scene.materials[mesh.material];
      const Vec3f radiance = material.emission;
      // The emitting side is the object's winding normal transformed as a
      // normal (as at a hit, render/surface.h): the world edges' cross
      // product, turned around where the transform swaps handedness.
      // (Two-sided emitters keep their edges: where a sample lands does not
      // change for them.)
      const bool oneSided = !material.emitsBackSide;
      const bool swapEdges = oneSided && inst.transform.determinant() < 0;
      for (const Vec3i& tri : mesh.indices) {
        Vec3f p0 = inst.transform.transformPoint(mesh.positions[tri.x]);
        Vec3f e1 = inst.transform.transformPoint(mesh.positions[tri.y]) - p0;
        Vec3f e2 = inst.transform.transformPoint(mesh.positions[tri.z]) - p0;
        float area = 0.5f * length(cross(e1, e2));
        if (!(area > 0)) continue;
        if (swapEdges) std::swap(e1, e2);  // the same triangle, its normal turned
        triangles_.push_back({p0, e1, e2, radiance, area, oneSided});
      }
    }
  }
  if (triangles_.size() > kMaxIndividualTriangles) {
    for (size_t begin = 0; begin < triangles_.size(); begin += kTrianglesPerGroup) {
      Group g;
      std::vector<float> powers;
      for (size_t i = begin; i < std::min(triangles_.size(), begin + kTrianglesPerGroup); ++i) {
        const EmissiveTriangle& t = triangles_[i];
        g.triangles.push_back(uint32_t(i));
        float power = luminance(t.radiance) * t.area;
        powers.push_back(power);
        g.power += power;
        g.bounds.extend(t.p0);
        g.bounds.extend(t.p0 + t.e1);
        g.bounds.extend(t.p0 + t.e2);
      }
      g.byPower = Distribution1D(std::move(powers));
      groups_.push_back(std::move(g));
    }
  }
}

bool LightSampler::empty() const {
  return suns_.empty() && environment_.isBlack() && triangles_.empty();
}

Vec2f LightSampler::directionToUv(Vec3f d) const {
  float theta = std::acos(std::clamp(d.y, -1.0f, 1.0f));
  float phi = std::atan2(d.z, d.x) + environment_.rotation;
  float u = phi / (2 * kPi);
  u -= std::floor(u);
  return {u, theta / kPi};
}

Vec3f LightSampler::uvToDirection(Vec2f uv) const {
  float theta = uv.y * kPi;
  float phi = uv.x * 2 * kPi - environment_.rotation;
  float s = std::sin(theta);
  return {s * std::cos(phi), std::cos(theta), s * std::sin(phi)};
}

Vec3f LightSampler::environmentRadiance(Vec3f d) const {
  if (!environment_.image) return environment_.color;
  Vec2f uv = directionToUv(d);
  // HdrImage rows go top (theta = 0) to bottom; its sampler takes v = 0 at the bottom.
  return environment_.image->sampleBilinear({uv.x, 1 - uv.y}) * environment_.color;
}

Vec3f LightSampler::background(Vec3f d) const {
  Vec3f l = environmentRadiance(d);
  for (size_t i = 0; i < suns_.size(); ++i)
    // |d - s| <= 2 sin(r / 2) is the cone test without 1 - cos cancellation.
    if (length(d - suns_[i].direction) <= sunConstants_[i].chordRadius)
      l += sunConstants_[i].radiance;
  return l;
}

bool LightSampler::sampleEnvironment(const Frame& frame, bool twoSided, Vec2f u,
                                     LightSample& out) const {
  if (!environment_.image && twoSided) {
    // Uniform over the sphere: light arrives from both sides.
    float z = 1 - 2 * u.x;
    float r = std::sqrt(std::max(0.0f, 1 - z * z));
    float sinPhi, cosPhi;
    sinCosTwoPi(u.y, sinPhi, cosPhi);
    out.direction = {r * cosPhi, r * sinPhi, z};
    out.pdf = 1 / (4 * kPi);
    out.radiance = environment_.color;
  } else if (!environment_.image) {
    // Constant: cosine-weighted around the normal is the ideal density.
    Vec3f local = sampleCosineHemisphere(u);
    out.direction = frame.toWorld(local);
    out.pdf = local.z / kPi;
    out.radiance = environment_.color;
  } else {
    float pdfUv;
    Vec2f uv = environmentDistribution_.sample(u, pdfUv);
    float sinTheta = std::sin(uv.y * kPi);
    if (sinTheta <= 0 || pdfUv <= 0) return false;
    out.direction = uvToDirection(uv);
    out.pdf = pdfUv / (2 * kPi * kPi * sinTheta);
    out.radiance = environmentRadiance(out.direction);
  }
  out.distance = kInfinity;
  return out.pdf > 0;
}

bool LightSampler::sampleTriangle(const EmissiveTriangle& t, Vec3f p, Vec2f u,
                                  LightSample& out) const {
  float su = std::sqrt(u.x);
  float b1 = 1 - su, b2 = u.y * su;
  Vec3f q = t.p0 + t.e1 * b1 + t.e2 * b2;
  Vec3f d = q - p;
  float dist2 = dot(d, d);
  if (dist2 <= 0) return false;
  float dist = std::sqrt(dist2);
  out.direction = d * (1 / dist);
  Vec3f ng = normalize(cross(t.e1, t.e2));
  const float facing = dot(ng, out.direction);
  // A one-sided emitter lights only points on the side its normal faces
  // (the direction runs from the point to the light: facing < 0).
  if (t.oneSided && !(facing < 0)) return false;
  float cosLight = std::abs(facing);
  if (cosLight <= 1e-7f) return false;
  out.distance = dist;
  out.normal = ng;
  out.radiance = t.radiance;
  out.pdf = dist2 / (cosLight * t.area);
  return true;
}

bool LightSampler::sample(Vec3f p, const Frame& frame, bool twoSided, float uSelect, Vec2f u,
                          LightSample& out) const {
  const Vec3f n = frame.n;
  // Candidate weights estimate each light's unshadowed contribution but are
  // never zero for a light that could contribute, which keeps the estimator
  // unbiased. Candidate i is chosen with probability w_i / sum(w): one pass
  // sums the weights, a second stops at the first candidate whose running sum
  // passes uSelect * sum (two cheap passes instead of a division per
  // candidate, which a streaming reservoir needs).
  const int sunCount = int(suns_.size());
  const int envIndex = sunCount;
  const int triangleBase = envIndex + 1;
  auto triangleWeight = [&](const Vec3f& center, float power, float area) {
    Vec3f d = center - p;
    return power / std::max(dot(d, d), area);
  };
  // Calls visit(index, weight) for each candidate in order until it returns true.
  auto forEachCandidate = [&](auto&& visit) {
    for (int i = 0; i < sunCount; ++i)
      if (visit(i, sunConstants_[i].selectionWeight *
                       std::max(std::abs(dot(n, suns_[i].direction)), 1e-3f)))
        return;
    if (!environment_.isBlack() && visit(envIndex, environmentWeight_)) return;
    int next = triangleBase;
    if (groups_.empty()) {
      for (const EmissiveTriangle& t : triangles_) {
        Vec3f c = t.p0 + (t.e1 + t.e2) * (1.0f / 3);
        if (visit(next++, triangleWeight(c, luminance(t.radiance) * t.area, t.area))) return;
      }
    } else {
      for (const Group& g : groups_)
        if (visit(next++,
                  triangleWeight(g.bounds.center(), g.power, g.bounds.surfaceArea() * 0.25f)))
          return;
    }
  };
  float total = 0;
  forEachCandidate([&](int, float w) {
    if (w > 0) total += w;
    return false;
  });
  if (!(total > 0)) return false;
  const float target = uSelect * total;
  float running = 0, chosenWeight = 0;
  int chosen = -1;
  forEachCandidate([&](int i, float w) {
    if (!(w > 0)) return false;
    running += w;
    chosen = i;  // the last positive one if rounding keeps running <= target
    chosenWeight = w;
    return running > target;
  });
  const float selection = chosenWeight / total;

  if (chosen < envIndex) {
    const SunConstants& constants = sunConstants_[chosen];
    // Uniform in the sun's cone, in terms of 1 - cos(theta) so that a small
    // cone keeps its precision.
    float oneMinusCosTheta = u.x * constants.oneMinusCosRadius;
    float cosTheta = 1 - oneMinusCosTheta;
    float sinTheta = std::sqrt(std::max(0.0f, oneMinusCosTheta * (2 - oneMinusCosTheta)));
    float sinPhi, cosPhi;
    sinCosTwoPi(u.y, sinPhi, cosPhi);
    out.direction = constants.frame.toWorld({sinTheta * cosPhi, sinTheta * sinPhi, cosTheta});
    out.distance = kInfinity;
    out.radiance = constants.radiance;
    out.pdf = constants.conePdf * selection;
    return true;
  }
  if (chosen == envIndex) {
    if (!sampleEnvironment(frame, twoSided, u, out)) return false;
    out.pdf *= selection;
    return true;
  }
  int index = chosen - triangleBase;
  if (groups_.empty()) {
    if (!sampleTriangle(triangles_[index], p, u, out)) return false;
    out.pdf *= selection;
    return true;
  }
  const Group& g = groups_[index];
  // Reuse u.x for the triangle choice, then stretch it back to [0, 1).
  float probability;
  int local = g.byPower.sampleDiscrete(u.x, probability);
  float lo = 0;
  for (int i = 0; i < local; ++i) lo += g.byPower.discreteProbability(i);
  Vec2f uTriangle{std::clamp((u.x - lo) / std::max(probability, 1e-12f), 0.0f, 0.99999994f), u.y};
  if (!sampleTriangle(triangles_[g.triangles[local]], p, uTriangle, out)) return false;
  out.pdf *= selection * probability;
  return true;
}

}  // namespace ferry
