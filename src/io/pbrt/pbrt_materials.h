// pbrt materials and textures mapped onto Ferry's Material (base colour with
// an optional texture, roughness, metallic, transmission, ior, emission,
// alpha cut-out, a dielectric coat, Oren-Nayar sigma, bump map, mix link).
//
// Materials (v3 and v4 names):
//   diffuse, matte, translucent, diffusetransmission -> diffuse: reflectance
//       / Kd (plus transmittance for diffusetransmission, clamped to 1: a thin
//       translucent sheet lit from both sides looks about that bright);
//       matte's sigma is Oren-Nayar
//   plastic -> Kd plus a GGX coat of Ks with pbrt-v3's FresnelDielectric(1.5,
//       1) (Coat::Additive); substrate -> pbrt-v3's FresnelBlend;
//       coateddiffuse -> the base under a layered dielectric coat
//   conductor, metal, coatedconductor -> metallic 1; the colour is the
//       normal-incidence Fresnel reflectance computed per wavelength from
//       eta and k (named spectra, .spd files, inline spectra, or rgb per
//       channel), or `reflectance` when given
//   dielectric, glass, thindielectric -> transmission 1 with eta (index);
//       thindielectric uses ior 1.01 (light passes straight through a thin
//       sheet; a solid-glass ior would bend it)
//   uber -> glass when Kt dominates, a mirror-like conductor when Kr
//       dominates Kd, else Kd plus a coat of Ks; opacity becomes a cut-out
//   disney -> color, metallic, roughness, spectrans
//   mix -> the first material, switching to the second with probability
//       amount at each shading point (v3's amount weighs the first, v4's the
//       second; Material::mixedWith)
//   interface, none, "" -> invisible (cut out everywhere)
//   fourier (pbrt-v3) -> its "bsdffile" read (io/pbrt/fourier_bsdf_file.h) into
//       Scene::bsdfTables, once per file; a file that is not there is a
//       warning naming it and grey diffuse 0.5, a malformed one an error
//   anything else (measured, hair, subsurface, ...) -> diffuse with
//       its Kd / reflectance if constant, else grey 0.5, one warning naming it
// Roughness: Ferry's roughness r has GGX alpha = r^2. pbrt-v4 remaps
// roughness to alpha = sqrt(roughness), pbrt-v3 with its polynomial; u and v
// roughnesses are combined as sqrt(alpha_u alpha_v).
//
// Textures: imagemap (PNG, TGA, JPEG, BMP, EXR, HDR, PFM; scale, invert,
// encoding/gamma, uscale/vscale/udelta/vdelta), checkerboard (2D), scale,
// mix, bilerp, constant, nested to any depth. A colour texture becomes an
// 8-bit sRGB RGBA texture: an image alone at its own resolution, anything
// else (procedural, nested, or with a uv transform) baked over uv in [0,1]^2
// on a grid (the largest image's resolution, or 16 texels per checker, up to
// 2048), repeating beyond; values above 1 are clamped. A float texture used
// as `alpha` becomes the alpha channel of such a texture (an image's alpha
// channel, or its luminance when it has none). Float textures on scalar
// parameters (roughness, amount) are averaged over uv (one warning).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "io/load_options.h"
#include "io/pbrt/pbrt_params.h"
#include "io/pbrt/pbrt_spectra.h"
#include "scene/scene.h"

namespace ferry {

struct PbrtTextureDefinition {
  std::string name;
  bool isFloat = false;   // "float"; else "spectrum" (v3: "color", "rgb")
  std::string className;  // imagemap, checkerboard, ...
  PbrtParams params;
  SourceLocation where;
  Affine3f transform;  // the CTM where it was defined (solid textures' space)
};

struct PbrtMaterialDefinition {
  std::string type;
  PbrtParams params;
  SourceLocation where;
  std::string name;  // for named materials; anonymous: empty
};

class PbrtMaterials {
 public:
  // `resolve` turns a file name written in the scene into a path (relative
  // names against the scene's directory); it throws InputError for missing
  // files, naming `where`.
  using Resolver = std::function<std::string(const std::string& name, const SourceLocation& where)>;
  PbrtMaterials(Scene& scene, LoadWarnings& warnings, Resolver resolve);
  ~PbrtMaterials();

  void defineTexture(PbrtTextureDefinition definition);
  // Returns the definition's id for materialFor().
  int32_t addMaterial(PbrtMaterialDefinition definition);
  void nameMaterial(const std::string& name, int32_t definition);
  std::optional<int32_t> namedMaterial(const std::string& name) const;

  // The Ferry material for shapes of `definition` (-1: pbrt's default, diffuse
  // 0.5) emitting `emission` (area light) and cut out by `alphaTexture`.
  // `emitsBackSide`: false for a one-sided area light (pbrt's default).
  int32_t materialFor(int32_t definition, Vec3f emission, int32_t alphaTexture,
                      bool emitsBackSide = true);
  // A shape's "alpha" (float or float texture) as an alpha texture;
  // kNoTexture when it is the constant 1.
  int32_t shapeAlpha(const PbrtParams& shapeParams);

  // A colour-valued parameter that cannot be a texture (lights): rgb,
  // spectrum (named, .spd file, inline) or blackbody ([T] normalised to
  // luminance 1 as in v4, [T scale] peak-normalised times scale as in v3).
  Vec3f constantColor(const PbrtParams& params, const std::string& name, Vec3f fallback,
                      SpectrumUse use);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ferry
