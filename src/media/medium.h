// A participating medium as pbrt defines one: absorption and scattering
// coefficients per RGB channel (per unit of world length, at density 1), a
// Henyey-Greenstein phase function, emitted radiance, and a density that
// scales the coefficients: 1 everywhere (homogeneous) or a grid over a box
// (pbrt-v3's heterogeneous, pbrt-v4's uniformgrid), 0 outside the box.
// Where a medium is, is said by the surfaces that bound it (their
// MediumInterface) and the camera's medium; a medium itself is unbounded.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/math.h"
#include "media/density_grid.h"
#include "media/majorant_grid.h"
#include "media/transfer_function.h"

namespace ferry {

// Which medium is on each side of a surface: indices into Scene::media,
// kNoMedium for vacuum. `outside` is on the side the surface's geometric
// normal points to. A surface with inside == outside bounds no medium: a
// ray scattering there stays in the medium it was in (pbrt's rule).
constexpr int32_t kNoMedium = -1;
struct MediumInterface {
  int32_t inside = kNoMedium;
  int32_t outside = kNoMedium;

  bool isTransition() const { return inside != outside; }
  // The medium a ray leaving the surface along `direction` enters.
  int32_t along(Vec3f direction, Vec3f geometricNormal) const {
    return dot(direction, geometricNormal) > 0 ? outside : inside;
  }
  bool operator==(const MediumInterface&) const = default;
};

struct Medium {
  std::string name;
  Vec3f sigmaA{0, 0, 0};    // absorption at density 1 (pbrt's sigma_a times scale)
  Vec3f sigmaS{0, 0, 0};    // scattering at density 1
  float g = 0;              // Henyey-Greenstein asymmetry, in (-1, 1)
  Vec3f emission{0, 0, 0};  // radiance emitted where light is absorbed (pbrt-v4's Le x Lescale)
  // Null: homogeneous (density 1 everywhere). Else the density over the box
  // that gridFromWorld maps to the unit cube, with its majorants.
  std::shared_ptr<const DensityGrid> density;
  std::shared_ptr<const MajorantGrid> majorants;
  Affine3f gridFromWorld;
  // A sci-vis volume: the grid holds values in [0, 1] that this maps to
  // extinction and albedo (sigmaA and sigmaS are then unused).
  std::shared_ptr<const TransferFunction> transfer;

  bool homogeneous() const { return density == nullptr; }
  Vec3f sigmaT() const { return sigmaA + sigmaS; }
  // A grid medium's coefficients at `unit` (the unit cube's coordinates).
  void coefficients(Vec3f unit, Vec3f& sa, Vec3f& ss) const {
    const float v = density->lookup(unit);
    if (transfer) {
      const float t = transfer->scale() * transfer->opacity(v);
      ss = transfer->color(v) * t;
      sa = Vec3f(t) - ss;
    } else {
      sa = sigmaA * v;
      ss = sigmaS * v;
    }
  }
  bool emits() const { return maxComponent(emission) > 0; }
  // Bytes it holds (its grid and majorants).
  size_t bytes() const;
};

// A grid medium: the density over `box` (in the medium's space, which
// `worldFromMedium` places; pbrt's p0 and p1 under the CTM at MakeNamedMedium).
Medium gridMedium(std::string name, Vec3f sigmaA, Vec3f sigmaS, float g,
                  std::shared_ptr<const DensityGrid> density, const Affine3f& worldFromMedium,
                  const Box3f& box);
// A sci-vis volume: values in [0, 1] over `box` (world space), rendered
// through `transfer` (isotropic scattering).
Medium transferFunctionMedium(std::string name, std::shared_ptr<const DensityGrid> values,
                              std::shared_ptr<const TransferFunction> transfer, const Box3f& box);
// Rebuilds the majorants after the transfer function changed.
void setTransferFunction(Medium& medium, std::shared_ptr<const TransferFunction> transfer);

}  // namespace ferry
