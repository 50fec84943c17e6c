// Scattering at a surface point, in the local shading frame (normal = +z).
// Directions point away from the surface: wo towards where the path came
// from, wi towards where it goes next.
//
// A Bsdf holds one lobe by value: any trivially copyable type with
//   Vec3f eval(Vec3f wo, Vec3f wi) const;   // f(wo, wi) |cos(wi)|, 0 for delta lobes
//   float pdf(Vec3f wo, Vec3f wi) const;    // sample()'s solid-angle density, 0 for delta
//   bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const;
// and, where one pass computes both for less (a tabulated BSDF),
//   Vec3f evalPdf(Vec3f wo, Vec3f wi, float& pdf) const;  // eval, and pdf into `pdf`
// which must give exactly what eval and pdf give.
// A material model (material/material_model.h) makes one per shading point.
#pragma once

#include <cstring>
#include <type_traits>

#include "core/math.h"

namespace ferry {

struct BsdfSample {
  Vec3f wi;
  Vec3f weight;   // f * |cos(wi)| / pdf
  float pdf = 0;  // solid angle; meaningless for delta lobes
  bool delta = false;
};

class Bsdf {
 public:
  // The largest lobe a Bsdf holds in place.
  static constexpr size_t kCapacity = 72;

  // Scatters nothing.
  Bsdf();
  // `delta`: every direction sample() draws is a delta (a mirror or a smooth
  // window); `transmits`: light may leave on the other side of the surface,
  // or its two sides scatter differently (a tabulated BSDF with a distinct
  // bottom): the sign of wo.z then says which side it arrived from; the
  // others are shaded on the side the ray arrived from.
  template <class Lobe>
  Bsdf(const Lobe& lobe, bool delta, bool transmits);

  bool isDelta() const { return delta_; }
  bool transmits() const { return transmits_; }

  // f(wo, wi) * |cos(wi)|; zero for delta lobes.
  Vec3f eval(Vec3f wo, Vec3f wi) const { return ops_->eval(storage_, wo, wi); }
  // Solid-angle density with which sample() picks wi; zero for delta lobes.
  float pdf(Vec3f wo, Vec3f wi) const { return ops_->pdf(storage_, wo, wi); }
  // eval(wo, wi), and pdf(wo, wi) into `pdf` when it is not null: the same
  // numbers, in one pass where the lobe has one.
  Vec3f evalPdf(Vec3f wo, Vec3f wi, float* pdf) const {
    return ops_->evalPdf(storage_, wo, wi, pdf);
  }
  // Draws wi from (uLobe, u); false when no direction is produced.
  bool sample(Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) const {
    return ops_->sample(storage_, wo, uLobe, u, out);
  }

  // The lobe, if it is a `Lobe` (for tests and diagnostics).
  template <class Lobe>
  const Lobe* as() const {
    return ops_ == &kOps<Lobe> ? reinterpret_cast<const Lobe*>(storage_) : nullptr;
  }

 private:
  struct Ops {
    Vec3f (*eval)(const void* lobe, Vec3f wo, Vec3f wi);
    float (*pdf)(const void* lobe, Vec3f wo, Vec3f wi);
    bool (*sample)(const void* lobe, Vec3f wo, float uLobe, Vec2f u, BsdfSample& out);
    Vec3f (*evalPdf)(const void* lobe, Vec3f wo, Vec3f wi, float* pdf);
  };
  template <class Lobe>
  static constexpr Ops kOps = {
      [](const void* l, Vec3f wo, Vec3f wi) { return static_cast<const Lobe*>(l)->eval(wo, wi); },
      [](const void* l, Vec3f wo, Vec3f wi) { return static_cast<const Lobe*>(l)->pdf(wo, wi); },
      [](const void* l, Vec3f wo, float uLobe, Vec2f u, BsdfSample& out) {
        return static_cast<const Lobe*>(l)->sample(wo, uLobe, u, out);
      },
      [](const void* l, Vec3f wo, Vec3f wi, float* pdf) {
        const Lobe& lobe = *static_cast<const Lobe*>(l);
        if constexpr (requires(float& p) { lobe.evalPdf(wo, wi, p); }) {
          if (pdf) return lobe.evalPdf(wo, wi, *pdf);
        } else {
          if (pdf) *pdf = lobe.pdf(wo, wi);
        }
        return lobe.eval(wo, wi);
      }};

  alignas(16) unsigned char storage_[kCapacity];
  const Ops* ops_;
  bool delta_ = false;
  bool transmits_ = false;
};

template <class Lobe>
Bsdf::Bsdf(const Lobe& lobe, bool delta, bool transmits)
    : ops_(&kOps<Lobe>), delta_(delta), transmits_(transmits) {
  static_assert(std::is_trivially_copyable_v<Lobe> && std::is_trivially_destructible_v<Lobe>,
                "a lobe is plain data");
  static_assert(sizeof(Lobe) <= kCapacity && alignof(Lobe) <= 16, "a lobe fits a Bsdf");
  std::memcpy(storage_, &lobe, sizeof(Lobe));
}

// Fresnel reflectance of a dielectric interface; eta = n_transmitted / n_incident.
float fresnelDielectric(float cosThetaI, float eta);
// A cosine-weighted direction about +z (inline: every diffuse bounce and
// constant-sky light sample takes one).
[[gnu::always_inline]] inline Vec3f sampleCosineHemisphere(Vec2f u) {
  float r = std::sqrt(u.x);
  float sinPhi, cosPhi;
  sinCosTwoPi(u.y, sinPhi, cosPhi);
  return {r * cosPhi, r * sinPhi, std::sqrt(std::max(0.0f, 1 - u.x))};
}

}  // namespace ferry
