#include "material/models/layered.h"

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>

#include <fmt/format.h>

#include "core/random.h"
#include "material/microfacet.h"

namespace ferry {
namespace {

using namespace microfacet;

constexpr uint8_t kReflection = 1, kTransmission = 2, kBothSides = 3;
constexpr float kOneBelowOne = 0x1.fffffep-1f;

// One scattering event at a layer: f (not times the cosine) and its density.
struct Scatter {
  Vec3f wi{0};
  float f = 0;  // the layers' own f is grey; colour comes from the base and the slab
  Vec3f tint{1};
  float pdf = 0;
  bool specular = false;
  bool transmission = false;
  bool valid() const { return pdf > 0 && f > 0 && wi.z != 0 && maxComponent(tint) > 0; }
  Vec3f value() const { return tint * f; }
};

// Random numbers drawn from a hash: the same inputs, the same walk.
struct WalkRandom {
  uint32_t state;
  float operator()() {
    state = hashMix(state + 0x9e3779b9u);
    return std::min(float(state >> 8) * 0x1p-24f, kOneBelowOne);
  }
};

uint32_t hashOf(Vec3f v, uint32_t seed) {
  seed = hashCombine(seed, std::bit_cast<uint32_t>(v.x));
  seed = hashCombine(seed, std::bit_cast<uint32_t>(v.y));
  return hashCombine(seed, std::bit_cast<uint32_t>(v.z));
}

float powerHeuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0 ? a2 / (a2 + b2) : 0;
}

// Fresnel reflectance with cosI of either sign (negative: from inside).
float fresnel(float cosI, float eta) {
  return cosI >= 0 ? fresnelDielectric(cosI, eta) : fresnelDielectric(-cosI, 1 / eta);
}

// The slab's transmittance over a vertical distance dz along w.
float slabTransmittance(float dz, Vec3f w) {
  if (std::abs(dz) <= FLT_MIN) return 1;
  return std::exp(-std::abs(dz / w.z));
}

// Density of GGX normals visible from w (either side), pbrt-v4's D(w, wm).
float visibleDensity(Vec3f w, Vec3f m, float alpha) {
  if (w.z == 0) return 0;
  return ggxG1(w, alpha) / std::abs(w.z) * ggxD(m, alpha) * std::abs(dot(w, m));
}

// A dielectric interface of relative index eta (below over above), GGX
// width alpha. `radiance`: light carried towards the camera (transmission
// scales by 1 / eta'^2); false: importance, the adjoint.
struct Interface {
  float eta;
  float alpha;

  bool smooth() const { return alpha < kSmoothAlpha; }

  // The microfacet normal that takes wo to wi (the generalized half vector,
  // towards +z) and the relative index along the way (1 for a reflection);
  // false where none does (grazing, or a back-facing microfacet).
  bool halfVector(Vec3f wo, Vec3f wi, Vec3f& m, float& etap) const {
    const float cosO = wo.z, cosI = wi.z;
    if (cosO == 0 || cosI == 0) return false;
    etap = cosO * cosI > 0 ? 1 : (cosO > 0 ? eta : 1 / eta);
    m = wi * etap + wo;
    if (dot(m, m) == 0) return false;
    m = normalize(m);
    if (m.z < 0) m = -m;
    return !(dot(m, wi) * cosI < 0 || dot(m, wo) * cosO < 0);
  }

  float f(Vec3f wo, Vec3f wi, bool radiance) const {
    Vec3f m;
    float etap;
    if (smooth() || !halfVector(wo, wi, m, etap)) return 0;
    const float fr = fresnel(dot(wo, m), eta);
    if (wo.z * wi.z > 0)
      return ggxD(m, alpha) * ggxG2(wo, wi, alpha) * fr / std::abs(4 * wi.z * wo.z);
    const float s = dot(wi, m) + dot(wo, m) / etap;
    const float denom = s * s * wi.z * wo.z;
    float ft = ggxD(m, alpha) * (1 - fr) * ggxG2(wo, wi, alpha) *
               std::abs(dot(wi, m) * dot(wo, m) / denom);
    if (radiance) ft /= etap * etap;
    return ft;
  }

  float pdf(Vec3f wo, Vec3f wi, uint8_t sides) const {
    Vec3f m;
    float etap;
    if (smooth() || !halfVector(wo, wi, m, etap)) return 0;
    const float r = fresnel(dot(wo, m), eta);
    const float pr = sides & kReflection ? r : 0, pt = sides & kTransmission ? 1 - r : 0;
    if (pr == 0 && pt == 0) return 0;
    if (wo.z * wi.z > 0)
      return visibleDensity(wo, m, alpha) / (4 * std::abs(dot(wo, m))) * pr / (pr + pt);
    const float s = dot(wi, m) + dot(wo, m) / etap;
    return visibleDensity(wo, m, alpha) * std::abs(dot(wi, m)) / (s * s) * pt / (pr + pt);
  }

  Scatter sample(Vec3f wo, float uc, Vec2f u, bool radiance, uint8_t sides) const {
    Scatter s;
    if (smooth()) {
      const float r = fresnel(wo.z, eta);
      const float pr = sides & kReflection ? r : 0, pt = sides & kTransmission ? 1 - r : 0;
      if (pr == 0 && pt == 0) return s;
      s.specular = true;
      if (uc < pr / (pr + pt)) {
        s.wi = {-wo.x, -wo.y, wo.z};
        s.f = r / std::abs(s.wi.z);
        s.pdf = pr / (pr + pt);
        return s;
      }
      const bool above = wo.z > 0;
      const float etap = above ? eta : 1 / eta;
      if (!refract(wo, Vec3f(0, 0, above ? 1.0f : -1.0f), etap, s.wi)) return Scatter{};
      s.f = (1 - r) / std::abs(s.wi.z);
      if (radiance) s.f /= etap * etap;
      s.pdf = pt / (pr + pt);
      s.transmission = true;
      return s;
    }
    const Vec3f m = sampleVisibleNormal(wo.z < 0 ? -wo : wo, alpha, u);
    const float cosOM = dot(wo, m);
    const float r = fresnel(cosOM, eta);
    const float pr = sides & kReflection ? r : 0, pt = sides & kTransmission ? 1 - r : 0;
    if (pr == 0 && pt == 0) return s;
    if (uc < pr / (pr + pt)) {
      s.wi = reflect(wo, m);
      if (!(wo.z * s.wi.z > 0)) return Scatter{};
      s.pdf = visibleDensity(wo, m, alpha) / (4 * std::abs(cosOM)) * pr / (pr + pt);
      s.f = ggxD(m, alpha) * ggxG2(wo, s.wi, alpha) * r / (4 * std::abs(s.wi.z * wo.z));
      return s;
    }
    const float etap = cosOM > 0 ? eta : 1 / eta;
    if (!refract(wo, cosOM > 0 ? m : -m, etap, s.wi)) return Scatter{};
    if (wo.z * s.wi.z >= 0) return Scatter{};
    const float d = dot(s.wi, m) + cosOM / etap;
    const float denom = d * d;
    s.pdf = visibleDensity(wo, m, alpha) * std::abs(dot(s.wi, m)) / denom * pt / (pr + pt);
    s.f = (1 - r) * ggxD(m, alpha) * ggxG2(wo, s.wi, alpha) *
          std::abs(dot(s.wi, m) * cosOM / (s.wi.z * wo.z * denom));
    if (radiance) s.f /= etap * etap;
    s.transmission = true;
    return s;
  }
};

// The opaque base, lit from above: Lambertian, or a GGX conductor.
struct Base {
  Vec3f color;
  float alpha;  // negative: Lambertian

  bool diffuse() const { return alpha < 0; }
  bool specular() const { return !diffuse() && alpha < kSmoothAlpha; }

  Vec3f f(Vec3f wo, Vec3f wi) const {
    if (!(wo.z * wi.z > 0)) return Vec3f(0);
    if (diffuse()) return color * (1 / kPi);
    if (specular()) return Vec3f(0);
    if (wo.z < 0) wo = -wo, wi = -wi;
    const Vec3f m = normalize(wo + wi);
    return schlick(color, dot(wo, m)) * (ggxD(m, alpha) * ggxG2(wo, wi, alpha) / (4 * wo.z * wi.z));
  }

  float pdf(Vec3f wo, Vec3f wi) const {
    if (!(wo.z * wi.z > 0)) return 0;
    if (diffuse()) return std::abs(wi.z) / kPi;
    if (specular()) return 0;
    if (wo.z < 0) wo = -wo, wi = -wi;
    const Vec3f m = normalize(wo + wi);
    return visibleDensity(wo, m, alpha) / (4 * std::abs(dot(wo, m)));
  }

  Scatter sample(Vec3f wo, Vec2f u) const {
    Scatter s;
    const float side = wo.z < 0 ? -1.0f : 1.0f;
    if (diffuse()) {
      s.wi = sampleCosineHemisphere(u);
      s.wi.z *= side;
      s.pdf = std::abs(s.wi.z) / kPi;
      s.f = 1 / kPi;
      s.tint = color;
      return s;
    }
    const Vec3f up = wo * side;
    if (specular()) {
      s.wi = Vec3f(-wo.x, -wo.y, wo.z);
      s.tint = schlick(color, up.z);
      s.f = 1 / std::abs(s.wi.z);
      s.pdf = 1;
      s.specular = true;
      return s;
    }
    const Vec3f m = sampleVisibleNormal(up, alpha, u);
    const Vec3f wi = reflect(up, m);
    if (!(wi.z > 0)) return s;
    s.wi = wi * side;
    s.pdf = visibleDensity(up, m, alpha) / (4 * std::abs(dot(up, m)));
    s.tint = schlick(color, dot(up, m));
    s.f = ggxD(m, alpha) * ggxG2(up, wi, alpha) / (4 * up.z * wi.z);
    return s;
  }
};

// Henyey-Greenstein with pbrt's convention: wo and wi both point away, so
// g > 0 (forward) favours wi near -wo.
float henyeyGreenstein(Vec3f wo, Vec3f wi, float g) {
  const float cosTheta = -dot(wo, wi);  // between the directions of travel
  const float d = 1 + g * g - 2 * g * cosTheta;
  return (1 - g * g) / (4 * kPi * d * std::sqrt(std::max(d, 1e-12f)));
}

Vec3f sampleHenyeyGreenstein(Vec3f wo, float g, Vec2f u) {
  float cosTheta;
  if (std::abs(g) < 1e-3f) {
    cosTheta = 1 - 2 * u.x;
  } else {
    const float s = (1 - g * g) / (1 - g + 2 * g * u.x);
    cosTheta = (1 + g * g - s * s) / (2 * g);
  }
  cosTheta = std::clamp(cosTheta, -1.0f, 1.0f);
  const float sinTheta = std::sqrt(std::max(0.0f, 1 - cosTheta * cosTheta));
  float sinPhi, cosPhi;
  sinCosTwoPi(u.y, sinPhi, cosPhi);
  const Frame frame(-wo);  // about the direction of travel
  return frame.toWorld({sinTheta * cosPhi, sinTheta * sinPhi, cosTheta});
}

}  // namespace

Vec3f LayeredLobe::eval(Vec3f wo, Vec3f wi) const {
  if (wo.z < 0) wo = -wo, wi = -wi;
  if (!(wi.z > 0) || !(wo.z > 0)) return Vec3f(0);
  const Interface top{eta, alpha};
  const Base bottom{base, baseAlpha};
  const bool scatters = maxComponent(albedo) > 0;
  Vec3f f(top.f(wo, wi, true) * float(samples));
  WalkRandom r{hashOf(wi, hashOf(wo, 0x5bd1e995u))};
  for (int s = 0; s < samples; ++s) {
    // Into the slab along wo, and (the adjoint) along wi: the virtual light.
    float uc = r();
    const Scatter wos = top.sample(wo, uc, {r(), r()}, true, kTransmission);
    if (!wos.valid()) continue;
    uc = r();
    const Scatter wis = top.sample(wi, uc, {r(), r()}, false, kTransmission);
    if (!wis.valid()) continue;
    Vec3f beta(wos.f * std::abs(wos.wi.z) / wos.pdf);
    float z = thickness;
    Vec3f w = wos.wi;
    for (int depth = 0; depth < maxDepth; ++depth) {
      if (depth > 3 && maxComponent(beta) < 0.25f) {
        const float q = std::max(0.0f, 1 - maxComponent(beta));
        if (r() < q) break;
        beta = beta * (1 / (1 - q));
      }
      if (!scatters) {
        z = z == thickness ? 0 : thickness;
        beta = beta * slabTransmittance(thickness, w);
      } else {
        const float dz = -std::log(1 - r()) * std::abs(w.z);
        const float zp = w.z > 0 ? z + dz : z - dz;
        if (zp == z) continue;
        if (0 < zp && zp < thickness) {
          // Scattered in the slab: towards the virtual light, then on.
          const float weight =
              top.smooth() ? 1 : powerHeuristic(wis.pdf, henyeyGreenstein(-w, -wis.wi, g));
          f += beta * albedo *
               (henyeyGreenstein(-w, -wis.wi, g) * weight *
                slabTransmittance(zp - thickness, wis.wi) * wis.f / wis.pdf);
          const Vec3f next = sampleHenyeyGreenstein(-w, g, {r(), r()});
          const float phase = henyeyGreenstein(-w, next, g);
          if (!(phase > 0) || next.z == 0) continue;
          beta = beta * albedo;  // the phase function over its own density
          w = next;
          z = zp;
          if (z < thickness && w.z > 0 && !top.smooth()) {
            const float exit = top.f(-w, wi, true);
            if (exit > 0) {
              const float weight = powerHeuristic(phase, top.pdf(wi, -w, kTransmission));
              f += beta * (slabTransmittance(zp - thickness, w) * exit * weight);
            }
          }
          continue;
        }
        z = std::clamp(zp, 0.0f, thickness);
      }
      if (z == thickness) {
        // Back at the interface from below: reflected into the slab again.
        uc = r();
        const Scatter bs = top.sample(-w, uc, {r(), r()}, true, kReflection);
        if (!bs.valid()) break;
        beta = beta * bs.value() * (std::abs(bs.wi.z) / bs.pdf);
        w = bs.wi;
        continue;
      }
      // At the base: towards the virtual light, then a new direction.
      if (!bottom.specular()) {
        const float weight = top.smooth() ? 1 : powerHeuristic(wis.pdf, bottom.pdf(-w, -wis.wi));
        f += beta * bottom.f(-w, -wis.wi) *
             (std::abs(wis.wi.z) * weight * slabTransmittance(thickness, wis.wi) * wis.f / wis.pdf);
      }
      const Scatter bs = bottom.sample(-w, {r(), r()});
      if (!bs.valid()) break;
      beta = beta * bs.value() * (std::abs(bs.wi.z) / bs.pdf);
      w = bs.wi;
      if (!top.smooth()) {
        // Out along the sampled direction, weighed against the virtual light
        // by the density with which sampling from wi finds that direction
        // (pbrt-v4 takes the reverse density, which biases eval() upwards).
        const float exit = top.f(-w, wi, true);
        if (exit > 0) {
          const float weight =
              bottom.specular() ? 1 : powerHeuristic(bs.pdf, top.pdf(wi, -w, kTransmission));
          f += beta * (slabTransmittance(thickness, bs.wi) * exit * weight);
        }
      }
    }
  }
  return f * (wi.z / float(samples));
}

float LayeredLobe::pdf(Vec3f wo, Vec3f wi) const {
  if (wo.z < 0) wo = -wo, wi = -wi;
  if (!(wi.z > 0) || !(wo.z > 0)) return 0;
  const Interface top{eta, alpha};
  const Base bottom{base, baseAlpha};
  WalkRandom r{hashOf(wo, hashOf(wi, 0x27d4eb2fu))};
  float sum = float(samples) * top.pdf(wo, wi, kReflection);
  for (int s = 0; s < samples; ++s) {
    // In through the interface, off the base, out through the interface.
    float uc = r();
    const Scatter wos = top.sample(wo, uc, {r(), r()}, true, kTransmission);
    uc = r();
    const Scatter wis = top.sample(wi, uc, {r(), r()}, false, kTransmission);
    if (!wos.valid() || !wis.valid()) continue;
    if (top.smooth()) {
      sum += bottom.pdf(-wos.wi, -wis.wi);
      continue;
    }
    const Scatter rs = bottom.sample(-wos.wi, {r(), r()});
    if (!rs.valid()) continue;
    if (bottom.specular()) {
      sum += top.pdf(-rs.wi, wi, kBothSides);
      continue;
    }
    const float rPdf = bottom.pdf(-wos.wi, -wis.wi);
    sum += powerHeuristic(wis.pdf, rPdf) * rPdf;
    const float tPdf = top.pdf(-rs.wi, wi, kBothSides);
    sum += powerHeuristic(rs.pdf, tPdf) * tPdf;
  }
  // Mixed with the uniform sphere's, as pbrt-v4 does, so it is never 0.
  return 0.1f / (4 * kPi) + 0.9f * sum / float(samples);
}

bool LayeredLobe::sample(Vec3f woIn, float uLobe, Vec2f u, BsdfSample& out) const {
  const bool flip = woIn.z < 0;
  const Vec3f wo = flip ? -woIn : woIn;
  const Interface top{eta, alpha};
  const Base bottom{base, baseAlpha};
  auto finish = [&](Vec3f wi, Vec3f f, float pdf, bool specular) {
    out.wi = flip ? -wi : wi;
    out.weight = f * (std::abs(wi.z) / pdf);
    out.delta = specular;
    out.pdf = specular ? pdf : this->pdf(woIn, out.wi);
    return std::isfinite(out.weight.x + out.weight.y + out.weight.z) &&
           maxComponent(out.weight) > 0 && out.pdf > 0;
  };
  const Scatter first = top.sample(wo, uLobe, u, true, kBothSides);
  if (!first.valid()) return false;
  if (!first.transmission) return finish(first.wi, first.value(), first.pdf, first.specular);
  WalkRandom r{hashOf(Vec3f(uLobe, u.x, u.y), hashOf(wo, 0x9e3779b9u))};
  const bool scatters = maxComponent(albedo) > 0;
  Vec3f f = first.value() * std::abs(first.wi.z);
  float pdf = first.pdf;
  bool specular = first.specular;
  float z = thickness;
  Vec3f w = first.wi;
  for (int depth = 0; depth < maxDepth; ++depth) {
    const float rrBeta = maxComponent(f) / pdf;
    if (depth > 3 && rrBeta < 0.25f) {
      const float q = std::max(0.0f, 1 - rrBeta);
      if (r() < q) return false;
      pdf *= 1 - q;
    }
    if (w.z == 0) return false;
    if (scatters) {
      const float dz = -std::log(1 - r()) * std::abs(w.z);
      const float zp = w.z > 0 ? z + dz : z - dz;
      if (zp == z) return false;
      if (0 < zp && zp < thickness) {
        const Vec3f next = sampleHenyeyGreenstein(-w, g, {r(), r()});
        const float phase = henyeyGreenstein(-w, next, g);
        if (!(phase > 0) || next.z == 0) return false;
        f = f * albedo * phase;
        pdf *= phase;
        specular = false;
        w = next;
        z = zp;
        continue;
      }
      z = std::clamp(zp, 0.0f, thickness);
    } else {
      z = z == thickness ? 0 : thickness;
      f = f * slabTransmittance(thickness, w);
    }
    const float uc = r();
    const Vec2f uu{r(), r()};
    const Scatter bs = z == 0 ? bottom.sample(-w, uu) : top.sample(-w, uc, uu, true, kBothSides);
    if (!bs.valid()) return false;
    f = f * bs.value();
    pdf *= bs.pdf;
    specular = specular && bs.specular;
    w = bs.wi;
    if (bs.transmission) return w.z > 0 && finish(w, f, pdf, specular);
    f = f * std::abs(bs.wi.z);
  }
  return false;
}

Bsdf layeredBsdf(const LayeredLobe& lobe) {
  return Bsdf(lobe, false, false);
}

Bsdf LayeredModel::bsdf(Vec3f color, const MaterialResources&) const {
  LayeredLobe lobe;
  lobe.base = max(color, Vec3f(0));
  lobe.baseAlpha = conductorBase ? baseAlpha : -1;
  lobe.eta = eta;
  lobe.alpha = alpha;
  lobe.thickness = std::max(thickness, FLT_MIN);
  lobe.albedo = albedo;
  lobe.g = g;
  lobe.maxDepth = uint16_t(maxDepth);
  lobe.samples = uint16_t(samples);
  return layeredBsdf(lobe);
}

void LayeredModel::write(MaterialRecordWriter& record) const {
  record.pod(uint8_t(conductorBase));
  record.pod(baseAlpha);
  record.pod(eta);
  record.pod(alpha);
  record.pod(thickness);
  record.pod(albedo);
  record.pod(g);
  record.pod(int32_t(maxDepth));
  record.pod(int32_t(samples));
}

std::shared_ptr<const MaterialModel> LayeredModel::read(MaterialRecordReader& record) {
  auto m = std::make_shared<LayeredModel>();
  const uint8_t conductor = record.pod<uint8_t>();
  if (conductor > 1) record.fail(fmt::format("conductor base is {}, not 0 or 1", conductor));
  m->conductorBase = conductor == 1;
  m->baseAlpha = record.number();
  m->eta = record.number();
  m->alpha = record.number();
  m->thickness = record.number();
  m->albedo = record.color();
  m->g = record.number();
  m->maxDepth = record.pod<int32_t>();
  m->samples = record.pod<int32_t>();
  if (!(m->eta > 0) || !(m->alpha >= 0) || !(m->thickness >= 0) || !(std::abs(m->g) < 1) ||
      m->maxDepth < 1 || m->maxDepth > 1000 || m->samples < 1 || m->samples > 1000)
    record.fail("a layered model's eta, widths, thickness, g, depth or samples out of range");
  return m;
}

std::string LayeredModel::describe() const {
  return fmt::format(
      "layered ({} base{}, interface eta {:g} alpha {:g}, thickness {:g}, albedo ({:g}, {:g}, "
      "{:g}), g {:g}, {} deep, {} samples)",
      conductorBase ? "conductor" : "diffuse",
      conductorBase ? fmt::format(" alpha {:g}", baseAlpha) : std::string(), eta, alpha, thickness,
      albedo.x, albedo.y, albedo.z, g, maxDepth, samples);
}

}  // namespace ferry
