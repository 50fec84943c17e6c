// pbrt materials and textures (v3 and v4 names) mapped onto Ferry's Material
// (base colour with an optional texture, emission, alpha cut-out, bump map,
// mix link) and its model (material/models/: each pbrt material type onto
// one). Colour textures become 8-bit sRGB textures (an image alone
// at its own resolution, anything else baked over uv in [0,1]^2); float
// textures on scalar parameters are averaged. Unsupported materials become
// diffuse with one warning naming them. The mapping, material by material:
// docs/formats.md, "pbrt".
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
  // pbrt-v3 maps world points to a solid texture's space by that CTM itself
  // (its IdentityMapping3D is given the texture-to-world transform);
  // pbrt-v4 by its inverse. The two agree for the usual identity.
  bool transformIsWorldToTexture = false;
};

struct PbrtMaterialDefinition {
  std::string type;
  PbrtParams params;
  SourceLocation where;
  std::string name;  // for named materials; anonymous: empty
};

// A cut-out as a shape or a material states it: Material's alpha fields.
struct PbrtAlpha {
  int32_t texture = kNoTexture;
  AlphaTest test = AlphaTest::Below;
  AlphaRays rays = AlphaRays::All;
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
  // 0.5) emitting `emission` (area light) and cut out by `alpha` (unless the
  // material cuts itself out: an interface, uber's opacity).
  // `emitsBackSide`: false for a one-sided area light (pbrt's default);
  // `lightSampledOnBackSide`: Material's flag of that name (pbrt-v3 under a
  // mirroring transform).
  int32_t materialFor(int32_t definition, Vec3f emission, PbrtAlpha alpha = {},
                      bool emitsBackSide = true, bool lightSampledOnBackSide = false);
  // The medium a subsurface material (a scene material materialFor made)
  // encloses, kNoMedium for other materials.
  int32_t interiorMedium(int32_t material) const;
  // Whether the file is known to be pbrt-v4's (a subsurface material's
  // parameters are read as its version reads them).
  void setV4File(bool v4);
  // Whether `definition` is pbrt's Material "" / "interface" / "none": a
  // surface that only bounds media.
  bool isInterface(int32_t definition) const;
  // A shape's cut-out, none when it has none. pbrt-v4: "alpha" (a float or
  // float texture) is a hole with probability 1 - alpha for every ray.
  // pbrt-v3 (`v3`): "alpha" cuts paths and "shadowalpha" shadow rays, each
  // only where it is 0 (a float other than 0 is none).
  PbrtAlpha shapeAlpha(const PbrtParams& shapeParams, bool v3);

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
