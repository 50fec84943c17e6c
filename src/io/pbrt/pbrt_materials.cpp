#include "io/pbrt/pbrt_materials.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>

#include <fmt/format.h>

#include "core/error.h"
#include "io/images/image_io.h"
#include "io/pbrt/fourier_bsdf_file.h"
#include "material/metallic_roughness.h"
#include "material/models/coated_conductor.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"
#include "material/models/diffuse_transmission.h"
#include "material/models/fourier.h"
#include "material/models/fresnel_blend.h"
#include "material/models/hair.h"
#include "material/models/layered.h"
#include "material/models/subsurface.h"
#include "material/models/thin_dielectric.h"
#include "media/medium_presets.h"

namespace ferry {
namespace {

constexpr int kMaxDepth = 32;        // nested textures and mixed materials
constexpr int kMaxBakeSide = 2048;   // texels per side of a baked texture
constexpr int kAverageGrid = 64;     // samples per side when averaging a texture
constexpr float kAverageSpace = 64;  // side of the cube a solid texture is averaged over
// Texture-tree evaluations for one bake: 8 per texel of the largest texture.
constexpr uint64_t kMaxEvaluations = uint64_t(8) * kMaxBakeSide * kMaxBakeSide;

struct Look {
  Material m;
  PbrtAlpha alpha;                 // from the material itself (interface, uber opacity)
  std::optional<Medium> interior;  // what a subsurface material encloses
};

// An image as linear float RGB (and alpha when it has one), for evaluation.
struct ImageData {
  int width = 0, height = 0;
  std::vector<Vec3f> rgb;    // row 0 at the top
  std::vector<float> alpha;  // empty: opaque
};

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool isHdrExtension(const std::string& path) {
  std::string ext = lower(std::filesystem::path(path).extension().string());
  return ext == ".exr" || ext == ".hdr" || ext == ".pfm";
}

float average(Vec3f c) {
  return (c.x + c.y + c.z) / 3.0f;
}

uint8_t toByte(float v) {
  return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
}

// pbrt-v3's RoughnessToAlpha.
float v3RoughnessToAlpha(float r) {
  float x = std::log(std::max(r, 1e-3f));
  return 1.62142f + 0.819955f * x + 0.1734f * x * x + 0.0171201f * x * x * x +
         0.000640711f * x * x * x * x;
}

bool isV3Material(const std::string& type) {
  return type == "matte" || type == "plastic" || type == "substrate" || type == "metal" ||
         type == "glass" || type == "uber" || type == "translucent" || type == "disney" ||
         type == "mirror";
}

}  // namespace

struct PbrtMaterials::Impl {
  Scene& scene;
  LoadWarnings& warnings;
  Resolver resolve;
  std::map<std::string, PbrtTextureDefinition> floatTextures, colorTextures;
  std::vector<PbrtMaterialDefinition> definitions;
  std::vector<std::optional<Look>> looks;
  std::vector<uint8_t> converting;
  std::map<std::string, int32_t> named;
  std::map<std::tuple<int32_t, float, float, float, int32_t, AlphaTest, AlphaRays, bool, bool>,
           int32_t>
      ferryMaterials;
  std::map<std::string, std::shared_ptr<const ImageData>> images;
  std::map<std::string, int32_t> bakedColor, bakedAlpha;
  std::map<const PbrtTextureDefinition*, int32_t> pointTextures_;
  std::map<const PbrtTextureDefinition*, bool> solidUse_;
  std::map<std::string, std::pair<int32_t, float>> bakedBump;
  std::map<int32_t, int32_t> mixTargets;  // definition -> its scene material
  std::map<std::string, float> averages;
  std::map<std::string, SampledSpectrum> spectrumFiles;
  std::map<std::string, int32_t> bsdfTables;  // resolved path -> Scene::bsdfTables
  std::map<int, int32_t> constantAlpha;
  std::map<int32_t, int32_t> interiors;  // scene material -> its subsurface medium
  bool v4File = false;                   // the file is known to be pbrt-v4's
  uint64_t evaluations_ = 0;             // of the current bake or average
  // Definitions whose class has been warned about: a bake evaluates a
  // texture per texel, and a warning's message is formatted once per definition.
  std::set<const PbrtTextureDefinition*> classWarned_;

  Impl(Scene& s, LoadWarnings& w, Resolver r) : scene(s), warnings(w), resolve(std::move(r)) {}

  void reportUnused(const PbrtParams& params, const std::string& what) {
    for (const PbrtParam* p : params.unused())
      warnings.once(what + "|" + p->declaration(),
                    fmt::format("{}: ignored parameter \"{}\" (not supported; first at {})", what,
                                p->declaration(), p->where.toString()));
  }

  // ------------------------------------------------------------------ spectra

  SampledSpectrum spectrumOf(const PbrtParam& p) {
    if (!p.strings.empty()) {
      const std::string& s = p.strings[0];
      if (auto named = namedSpectrum(s)) return *named;
      // pbrt-v4 knows more named spectra than Ferry tabulates (metal-CuZn,
      // camera sensors): a plausible stand-in and a warning, not an error.
      for (auto [prefix, standIn] :
           {std::pair{"metal-", "metal-Al"}, std::pair{"glass-", "glass-BK7"},
            std::pair{"stdillum-", "stdillum-D65"}}) {
        if (!s.starts_with(prefix) || s.find('.') != std::string::npos) continue;
        std::string name = standIn;
        if (name.starts_with("metal-")) name += s.ends_with("-k") ? "-k" : "-eta";
        warnings.once("spectrum|" + s,
                      fmt::format("named spectrum \"{}\" is not known to Ferry: using \"{}\" "
                                  "instead (first at {}; known: {})",
                                  s, name, p.where.toString(), namedSpectrumList()));
        return *namedSpectrum(name);
      }
      auto it = spectrumFiles.find(s);
      if (it != spectrumFiles.end()) return it->second;
      std::string path;
      try {
        path = resolve(s, p.where);
      } catch (const InputError& e) {
        throw InputError(p.where, fmt::format("\"{}\": '{}' is neither a named spectrum ({}) nor "
                                              "a file: {}",
                                              p.declaration(), s, namedSpectrumList(), e.what()));
      }
      SampledSpectrum spd;
      try {
        spd = readSpdFile(path);
      } catch (const InputError& e) {
        throw InputError(p.where, fmt::format("\"{}\": {}", p.declaration(), e.what()));
      }
      return spectrumFiles.emplace(s, spd).first->second;
    }
    auto s = SampledSpectrum::fromInterleaved(p.floats);
    if (!s) PbrtParams::fail(p, "wavelengths must increase");
    return *s;
  }

  // RGB of a non-texture colour parameter.
  Vec3f colorValue(const PbrtParam& p, SpectrumUse use) {
    if (p.type == "rgb") {
      if (p.floats.size() != 3) PbrtParams::fail(p, "expected one rgb value (3 numbers)");
      return max(Vec3f(p.floats[0], p.floats[1], p.floats[2]), Vec3f(0));
    }
    if (p.type == "float") {
      if (p.floats.size() != 1) PbrtParams::fail(p, "expected one value");
      return Vec3f(std::max(p.floats[0], 0.0f));
    }
    if (p.type == "spectrum") {
      SampledSpectrum s = spectrumOf(p);
      if (use == SpectrumUse::Illuminant && !p.strings.empty() && namedSpectrum(p.strings[0])) {
        // pbrt-v4 normalises named illuminants to luminance 1.
        float y = spectrumLuminance(s);
        return y > 0 ? spectrumToRgb(s, use) / y : Vec3f(0);
      }
      return spectrumToRgb(s, use);
    }
    if (p.type == "blackbody") {
      if (p.floats.empty() || p.floats.size() > 2)
        PbrtParams::fail(p, "expected a temperature (v4) or a temperature and a scale (v3)");
      SampledSpectrum s = blackbodySpectrum(p.floats[0]);
      Vec3f rgb = spectrumToRgb(s, SpectrumUse::Illuminant);
      if (p.floats.size() == 2) return rgb * p.floats[1];
      float y = spectrumLuminance(s);
      return y > 0 ? rgb / y : Vec3f(0);
    }
    PbrtParams::fail(p, "expected a colour (rgb, spectrum, blackbody or float)");
  }

  // Per channel value of a spectrum-like parameter (eta, k) at the R, G and B wavelengths.
  Vec3f perChannel(const PbrtParam& p) {
    if (p.type == "rgb" || p.type == "float") return colorValue(p, SpectrumUse::Reflectance);
    if (p.type == "spectrum") {
      SampledSpectrum s = spectrumOf(p);
      return {s.at(610), s.at(550), s.at(465)};
    }
    PbrtParams::fail(p, "expected a spectrum, rgb or float");
  }

  // --------------------------------------------------------------- textures

  const PbrtTextureDefinition* findTexture(const std::string& name, bool preferFloat) {
    auto& first = preferFloat ? floatTextures : colorTextures;
    auto& second = preferFloat ? colorTextures : floatTextures;
    auto it = first.find(name);
    if (it != first.end()) return &it->second;
    it = second.find(name);
    if (it != second.end()) return &it->second;
    return nullptr;
  }

  const PbrtTextureDefinition& textureOf(const PbrtParam& p, bool preferFloat) {
    if (p.strings.size() != 1) PbrtParams::fail(p, "expected one texture name");
    const PbrtTextureDefinition* t = findTexture(p.strings[0], preferFloat);
    if (!t) PbrtParams::fail(p, fmt::format("no texture named \"{}\" is defined", p.strings[0]));
    return *t;
  }

  // How 8-bit texels encode values: "srgb" (the default), "linear" or "gamma G"
  // (v4's encoding; v3's bool gamma: true is sRGB, false linear).
  std::string encodingOf(const PbrtTextureDefinition& t) {
    std::string encoding = lower(t.params.getString("encoding", ""));
    if (t.params.has("gamma")) {
      bool gamma = t.params.getBool("gamma", true);
      if (encoding.empty()) encoding = gamma ? "srgb" : "linear";
    }
    if (encoding.empty()) encoding = "srgb";
    if (encoding != "srgb" && encoding != "linear" && !encoding.starts_with("gamma "))
      throw InputError(t.where, fmt::format("texture \"{}\": unknown encoding \"{}\" (sRGB, "
                                            "linear or gamma G)",
                                            t.name, encoding));
    return encoding;
  }

  std::shared_ptr<const ImageData> image(const PbrtTextureDefinition& t) {
    std::string filename = t.params.getString("filename", "");
    if (filename.empty())
      throw InputError(t.where, fmt::format("imagemap texture \"{}\" has no filename", t.name));
    std::string encoding = encodingOf(t);
    std::string path = resolve(filename, t.where);
    std::string key = path + "|" + encoding;
    auto it = images.find(key);
    if (it != images.end()) return it->second;
    auto data = std::make_shared<ImageData>();
    try {
      if (isHdrExtension(path)) {
        HdrImage hdr = readHdrImage(path);
        data->width = hdr.width;
        data->height = hdr.height;
        data->rgb = std::move(hdr.pixels);
      } else {
        Texture tex = readTexture(path);
        data->width = tex.width;
        data->height = tex.height;
        data->rgb.resize(tex.texelCount());
        bool anyAlpha = false;
        float gamma = 0;
        if (encoding.starts_with("gamma ")) gamma = std::strtof(encoding.c_str() + 6, nullptr);
        for (size_t i = 0; i < data->rgb.size(); ++i) {
          const uint8_t* px = &tex.rgba[4 * i];
          Vec3f c;
          for (int k = 0; k < 3; ++k) {
            float v = px[k] / 255.0f;
            c[k] = encoding == "linear" ? v : gamma > 0 ? std::pow(v, gamma) : srgbToLinear(v);
          }
          data->rgb[i] = c;
          anyAlpha |= px[3] != 255;
        }
        if (anyAlpha) {
          data->alpha.resize(data->rgb.size());
          for (size_t i = 0; i < data->alpha.size(); ++i)
            data->alpha[i] = tex.rgba[4 * i + 3] / 255.0f;
        }
      }
    } catch (const InputError& e) {
      throw InputError(t.where, fmt::format("texture \"{}\": {}", t.name, e.what()));
    }
    images.emplace(key, data);
    return data;
  }

  struct Mapping {
    float su = 1, sv = 1, du = 0, dv = 0;
    bool identity() const { return su == 1 && sv == 1 && du == 0 && dv == 0; }
    Vec2f apply(Vec2f uv) const { return {su * uv.x + du, sv * uv.y + dv}; }
  };

  Mapping mappingOf(const PbrtTextureDefinition& t) {
    std::string type = t.params.getString("mapping", "uv");
    if (type != "uv")
      warnings.once("mapping|" + type,
                    fmt::format("texture mapping \"{}\" is not supported; using uv (first at {})",
                                type, t.where.toString()));
    return {t.params.getFloat("uscale", 1), t.params.getFloat("vscale", 1),
            t.params.getFloat("udelta", 0), t.params.getFloat("vdelta", 0)};
  }

  static Vec4f lookup(const ImageData& img, Vec2f uv, const std::string& wrap) {
    float x = uv.x * img.width - 0.5f, y = (1 - uv.y) * img.height - 0.5f;
    if (!std::isfinite(x)) x = 0;
    if (!std::isfinite(y)) y = 0;
    float fx = std::floor(x), fy = std::floor(y);
    float tx = x - fx, ty = y - fy;
    auto texel = [&](long ix, long iy) -> Vec4f {
      if (wrap == "clamp") {
        ix = std::clamp<long>(ix, 0, img.width - 1);
        iy = std::clamp<long>(iy, 0, img.height - 1);
      } else if (wrap == "black") {
        if (ix < 0 || iy < 0 || ix >= img.width || iy >= img.height) return {0, 0, 0, 1};
      } else {
        ix = ((ix % img.width) + img.width) % img.width;
        iy = ((iy % img.height) + img.height) % img.height;
      }
      size_t i = size_t(iy) * size_t(img.width) + size_t(ix);
      Vec3f c = img.rgb[i];
      return {c.x, c.y, c.z, img.alpha.empty() ? 1.0f : img.alpha[i]};
    };
    long ix = long(std::fmod(fx, 1 << 24)), iy = long(std::fmod(fy, 1 << 24));
    Vec4f a = texel(ix, iy), b = texel(ix + 1, iy), c = texel(ix, iy + 1),
          d = texel(ix + 1, iy + 1);
    auto mix = [&](float va, float vb, float vc, float vd) {
      return (va * (1 - tx) + vb * tx) * (1 - ty) + (vc * (1 - tx) + vd * tx) * ty;
    };
    return {mix(a.x, b.x, c.x, d.x), mix(a.y, b.y, c.y, d.y), mix(a.z, b.z, c.z, d.z),
            mix(a.w, b.w, c.w, d.w)};
  }

  // A float image's value: its alpha channel when it has one, else the mean of RGB.
  static float floatOf(const ImageData& img, Vec4f v) {
    return img.alpha.empty() ? (v.x + v.y + v.z) / 3.0f : v.w;
  }

  // A parameter of a texture at uv: constant, or another texture.
  Vec3f evalParam(const PbrtParams& params, const std::string& name, Vec3f fallback, Vec2f uv,
                  bool floatContext, int depth) {
    const PbrtParam* p = params.find(name);
    if (!p) return fallback;
    if (p->type == "texture") return eval(textureOf(*p, floatContext), uv, depth + 1);
    return colorValue(*p, SpectrumUse::Reflectance);
  }

  // Whether `t`'s class is to be warned about now: true once per definition.
  bool firstClassWarning(const PbrtTextureDefinition& t) { return classWarned_.insert(&t).second; }

  void unsupportedClass(const PbrtTextureDefinition& t) {
    if (!firstClassWarning(t)) return;
    warnings.once("texture class|" + t.className,
                  fmt::format("texture class \"{}\" is not supported; using the constant 0.5 "
                              "instead (first at {})",
                              t.className, t.where.toString()));
  }

  void warnCheckerboard3d(const PbrtTextureDefinition& t) {
    if (t.params.getInt("dimension", 2) != 2 && firstClassWarning(t))
      warnings.once("checkerboard3d", fmt::format("3D checkerboard textures are not supported; "
                                                  "using the 2D one (first at {})",
                                                  t.where.toString()));
  }

  void warnDirectionMix(const PbrtTextureDefinition& t) {
    if (firstClassWarning(t))
      warnings.once("directionmix", fmt::format("texture class \"directionmix\" is not "
                                                "supported; using the mean of tex1 and tex2 "
                                                "(first at {})",
                                                t.where.toString()));
  }

  // A texture's value at uv: linear RGB; float textures give grey.
  Vec3f eval(const PbrtTextureDefinition& t, Vec2f uv, int depth) {
    // Textures that use one texture twice double at every level: bound the work.
    if (evaluations_++ > kMaxEvaluations)
      throw InputError(t.where, fmt::format("texture \"{}\" is too expensive to bake (more than "
                                            "{} evaluations: textures nested too deeply?)",
                                            t.name, kMaxEvaluations));
    if (depth > kMaxDepth)
      throw InputError(t.where, fmt::format("texture \"{}\": textures nested more than {} deep "
                                            "(a texture that uses itself?)",
                                            t.name, kMaxDepth));
    const std::string& c = t.className;
    const bool f = t.isFloat;
    if (c == "constant") return evalParam(t.params, "value", Vec3f(1), uv, f, depth);
    if (c == "imagemap") {
      Mapping m = mappingOf(t);
      auto img = image(t);
      std::string wrap = t.params.getString("wrap", "repeat");
      Vec4f v = lookup(*img, m.apply(uv), wrap);
      Vec3f rgb = f ? Vec3f(floatOf(*img, v)) : v.xyz();
      rgb = rgb * t.params.getFloat("scale", 1);
      if (t.params.getBool("invert", false)) rgb = max(Vec3f(1) - rgb, Vec3f(0));
      return rgb;
    }
    if (c == "checkerboard") {
      warnCheckerboard3d(t);
      Mapping m = mappingOf(t);
      return checkerboardEven(m.apply(uv)) ? evalParam(t.params, "tex1", Vec3f(1), uv, f, depth)
                                           : evalParam(t.params, "tex2", Vec3f(0), uv, f, depth);
    }
    if (c == "scale") {
      // v4: tex * scale; v3: tex1 * tex2.
      if (t.params.has("tex1") || t.params.has("tex2"))
        return evalParam(t.params, "tex1", Vec3f(1), uv, f, depth) *
               evalParam(t.params, "tex2", Vec3f(1), uv, f, depth);
      return evalParam(t.params, "tex", Vec3f(1), uv, f, depth) *
             evalParam(t.params, "scale", Vec3f(1), uv, true, depth);
    }
    if (c == "mix") {
      float amount = average(evalParam(t.params, "amount", Vec3f(0.5f), uv, true, depth));
      return lerp(evalParam(t.params, "tex1", Vec3f(0), uv, f, depth),
                  evalParam(t.params, "tex2", Vec3f(1), uv, f, depth), amount);
    }
    if (c == "directionmix") {
      warnDirectionMix(t);
      return (evalParam(t.params, "tex1", Vec3f(0), uv, f, depth) +
              evalParam(t.params, "tex2", Vec3f(1), uv, f, depth)) *
             0.5f;
    }
    if (c == "dots") {
      return insideDot(mappingOf(t).apply(uv))
                 ? evalParam(t.params, "inside", Vec3f(1), uv, f, depth)
                 : evalParam(t.params, "outside", Vec3f(0), uv, f, depth);
    }
    if (c == "bilerp") {
      Vec2f st = mappingOf(t).apply(uv);
      float s = st.x - std::floor(st.x), u = st.y - std::floor(st.y);
      Vec3f v00 = evalParam(t.params, "v00", Vec3f(0), uv, f, depth);
      Vec3f v01 = evalParam(t.params, "v01", Vec3f(1), uv, f, depth);
      Vec3f v10 = evalParam(t.params, "v10", Vec3f(0), uv, f, depth);
      Vec3f v11 = evalParam(t.params, "v11", Vec3f(1), uv, f, depth);
      return lerp(lerp(v00, v10, s), lerp(v01, v11, s), u);
    }
    unsupportedClass(t);
    t.params.markAllUsed();
    return Vec3f(0.5f);
  }

  // The resolution a baked texture needs.
  void bakeSize(const PbrtTextureDefinition& t, int& width, int& height, float& frequency,
                int depth, std::set<const PbrtTextureDefinition*>& seen) {
    if (depth > kMaxDepth || !seen.insert(&t).second) return;
    if (t.className == "imagemap") {
      auto img = image(t);
      Mapping m = mappingOf(t);
      width = std::max(
          width, int(std::min<float>(kMaxBakeSide, img->width * std::max(1.0f, std::abs(m.su)))));
      height = std::max(
          height, int(std::min<float>(kMaxBakeSide, img->height * std::max(1.0f, std::abs(m.sv)))));
    }
    if (t.className == "checkerboard" || t.className == "dots") {
      Mapping m = mappingOf(t);
      frequency = std::max({frequency, std::abs(m.su), std::abs(m.sv)});
    }
    for (const PbrtParam& p : t.params.all())
      if (p.type == "texture" && p.strings.size() == 1)
        if (const PbrtTextureDefinition* sub = findTexture(p.strings[0], t.isFloat))
          bakeSize(*sub, width, height, frequency, depth + 1, seen);
  }

  // An imagemap that can be baked texel for texel from its file.
  bool isPlainImage(const PbrtTextureDefinition& t) {
    if (t.className != "imagemap") return false;
    Mapping m = mappingOf(t);
    return m.identity() && t.params.getString("mapping", "uv") == "uv";
  }

  WrapMode wrapOf(const PbrtTextureDefinition& t) {
    std::string wrap = t.params.getString("wrap", "repeat");
    if (wrap == "black")
      warnings.once("wrap|black", fmt::format("texture wrap mode \"black\": an image used directly "
                                              "clamps at its edges instead (first at {})",
                                              t.where.toString()));
    if (wrap == "clamp" || wrap == "black") return WrapMode::Clamp;
    if (wrap != "repeat")
      warnings.once("wrap|" + wrap, fmt::format("texture wrap mode \"{}\" is not supported; "
                                                "using repeat (first at {})",
                                                wrap, t.where.toString()));
    return WrapMode::Repeat;
  }

  int32_t addTexture(Texture texture) {
    scene.textures.push_back(std::move(texture));
    return int32_t(scene.textures.size() - 1);
  }

  int32_t bakeColor(const PbrtParam& p) {
    const PbrtTextureDefinition& t = textureOf(p, false);
    auto it = bakedColor.find(t.name);
    if (it != bakedColor.end()) return it->second;
    int32_t id = addTexture(bakedColorTexture(t));
    bakedColor.emplace(t.name, id);
    return id;
  }

  // A texture that uses no solid texture, as texels over uv: an 8-bit image
  // as it is, or the texture baked on a grid.
  Texture bakedColorTexture(const PbrtTextureDefinition& t) {
    Texture out;
    out.name = t.name;
    out.srgb = true;
    float scale = t.className == "imagemap" ? t.params.getFloat("scale", 1) : 1;
    bool invert = t.className == "imagemap" && t.params.getBool("invert", false);
    std::string encoding = t.className == "imagemap" ? encodingOf(t) : "";
    std::string filename = t.className == "imagemap" ? t.params.getString("filename", "") : "";
    if (isPlainImage(t) && !t.isFloat && !filename.empty() && !isHdrExtension(filename) &&
        encoding == "srgb") {
      // The common case: an 8-bit image as it is (changed in place for scale or invert).
      std::string path = resolve(filename, t.where);
      try {
        out = readTexture(path);
      } catch (const InputError& e) {
        throw InputError(t.where, fmt::format("texture \"{}\": {}", t.name, e.what()));
      }
      out.name = path;
      out.wrap = wrapOf(t);
      if (scale != 1 || invert)
        for (size_t i = 0; i < out.rgba.size(); i += 4)
          for (int k = 0; k < 3; ++k) {
            float v = srgbToLinear(out.rgba[i + k] / 255.0f) * scale;
            if (invert) v = std::max(0.0f, 1 - v);
            out.rgba[i + k] = toByte(linearToSrgb(v));
          }
    } else if (isPlainImage(t)) {
      auto img = image(t);
      out.width = img->width;
      out.height = img->height;
      out.wrap = wrapOf(t);
      out.rgba.resize(size_t(out.width) * out.height * 4);
      for (size_t i = 0; i < img->rgb.size(); ++i) {
        Vec3f c = img->rgb[i];
        if (t.isFloat) c = Vec3f(img->alpha.empty() ? average(c) : img->alpha[i]);
        c = c * scale;
        if (invert) c = max(Vec3f(1) - c, Vec3f(0));
        for (int k = 0; k < 3; ++k) out.rgba[4 * i + k] = toByte(linearToSrgb(c[k]));
        out.rgba[4 * i + 3] = 255;
      }
    } else {
      bakeGrid(t, out, false);
    }
    reportUnused(t.params, fmt::format("Texture \"{}\" \"{}\"", t.name, t.className));
    return out;
  }

  // The grid a texture is baked on: its images' resolution, else enough
  // texels for its finest pattern (at least 256 a side).
  void bakeResolution(const PbrtTextureDefinition& t, int& width, int& height) {
    width = height = 0;
    float frequency = 0;
    std::set<const PbrtTextureDefinition*> seen;
    bakeSize(t, width, height, frequency, 0, seen);
    if (width == 0 || height == 0) {
      const int side = std::clamp(int(std::ceil(32 * frequency)), 256, kMaxBakeSide);
      width = std::max(width, side);
      height = std::max(height, side);
    }
  }

  void bakeGrid(const PbrtTextureDefinition& t, Texture& out, bool alpha) {
    int width, height;
    bakeResolution(t, width, height);
    out.width = width;
    out.height = height;
    out.wrap = WrapMode::Repeat;
    out.rgba.assign(size_t(width) * height * 4, 255);
    evaluations_ = 0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        Vec2f uv((x + 0.5f) / width, 1 - (y + 0.5f) / height);
        Vec3f c = eval(t, uv, 0);
        uint8_t* px = &out.rgba[(size_t(y) * width + x) * 4];
        if (alpha) {
          px[3] = toByte(average(c));
        } else {
          for (int k = 0; k < 3; ++k) px[k] = toByte(linearToSrgb(c[k]));
        }
      }
  }

  // A float texture as a bump map's displacement: baked into a linear grey
  // texture spanning its range (only the slopes matter), `scale` set to the
  // range in world units. kNoTexture where it is flat.
  // A solid texture times constants (itself, or pbrt's "scale" of one with a
  // constant, nested): the solid texture's definition, `factor` the product.
  const PbrtTextureDefinition* scaledSolid(const PbrtTextureDefinition& t, float& factor,
                                           int depth = 0) {
    if (depth > 16) return nullptr;
    if (solidKind(t.className) != SolidTextureKind::None) return &t;
    if (t.className != "scale") return nullptr;
    const PbrtParam* a = t.params.find("tex1");
    const PbrtParam* b = t.params.find("tex2");
    if (!a || !b) return nullptr;
    if (a->type != "texture") std::swap(a, b);
    if (a->type != "texture" || b->type != "float" || b->floats.size() != 1) return nullptr;
    const PbrtTextureDefinition* inner = scaledSolid(textureOf(*a, true), factor, depth + 1);
    if (inner) factor *= b->floats[0];
    return inner;
  }

  int32_t bakeBump(const PbrtParam& p, float& scale) {
    const PbrtTextureDefinition& t = textureOf(p, true);
    auto it = bakedBump.find(t.name);
    if (it != bakedBump.end()) {
      scale = it->second.second;
      return it->second.first;
    }
    // A solid bump (fbm, wrinkled, ... or a scale of one): evaluated in 3D at
    // the shading point (render/surface.cpp), not baked over uv.
    float factor = 1;
    if (const PbrtTextureDefinition* solid = scaledSolid(t, factor)) {
      const int32_t id = pointTextureId(*solid);
      scale = factor;
      t.params.markAllUsed();
      bakedBump.emplace(t.name, std::make_pair(id, scale));
      return id;
    }
    if (usesSolid(t)) {  // a combination with a solid texture: also in 3D
      const int32_t id = pointTextureId(t);
      scale = 1;
      bakedBump.emplace(t.name, std::make_pair(id, scale));
      return id;
    }
    int width, height;
    bakeResolution(t, width, height);
    std::vector<float> values(size_t(width) * height);
    evaluations_ = 0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        values[size_t(y) * width + x] =
            average(eval(t, {(x + 0.5f) / width, 1 - (y + 0.5f) / height}, 0));
    const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
    const float low = *lo, range = *hi - *lo;
    int32_t id = kNoTexture;
    scale = 0;
    if (range > 0 && std::isfinite(range)) {
      Texture out;
      out.name = t.name + " (bump)";
      out.srgb = false;
      out.width = width;
      out.height = height;
      out.wrap = t.className == "imagemap" ? wrapOf(t) : WrapMode::Repeat;
      out.rgba.assign(values.size() * 4, 255);
      for (size_t i = 0; i < values.size(); ++i)
        for (int k = 0; k < 3; ++k) out.rgba[4 * i + k] = toByte((values[i] - low) / range);
      id = addTexture(std::move(out));
      scale = range;
    }
    reportUnused(t.params, fmt::format("Texture \"{}\" \"{}\"", t.name, t.className));
    bakedBump.emplace(t.name, std::make_pair(id, scale));
    return id;
  }

  int32_t bakeAlpha(const PbrtParam& p) {
    const PbrtTextureDefinition& t = textureOf(p, true);
    auto it = bakedAlpha.find(t.name);
    if (it != bakedAlpha.end()) return it->second;
    if (usesSolid(t)) {  // evaluated at the hit's world point (trace/alpha_cutout.h)
      const int32_t id = pointTextureId(t);
      bakedAlpha.emplace(t.name, id);
      return id;
    }
    Texture out;
    out.name = t.name;
    out.srgb = false;
    std::string filename = t.className == "imagemap" ? t.params.getString("filename", "") : "";
    if (isPlainImage(t) && !filename.empty() && !isHdrExtension(filename)) {
      std::string path = resolve(filename, t.where);
      try {
        out = readAlphaTexture(path);
      } catch (const InputError& e) {
        throw InputError(t.where, fmt::format("texture \"{}\": {}", t.name, e.what()));
      }
      out.name = path;
      out.wrap = wrapOf(t);
      float scale = t.params.getFloat("scale", 1);
      bool invert = t.params.getBool("invert", false);
      encodingOf(t);  // alpha is coverage: never decoded
      if (scale != 1 || invert)
        for (size_t i = 3; i < out.rgba.size(); i += 4) {
          float v = out.rgba[i] / 255.0f * scale;
          if (invert) v = std::max(0.0f, 1 - v);
          out.rgba[i] = toByte(v);
        }
    } else {
      bakeGrid(t, out, true);
    }
    reportUnused(t.params, fmt::format("Texture \"{}\" \"{}\"", t.name, t.className));
    int32_t id = addTexture(std::move(out));
    bakedAlpha.emplace(t.name, id);
    return id;
  }

  int32_t alphaConstant(float a) {
    int byte = toByte(a);
    auto it = constantAlpha.find(byte);
    if (it != constantAlpha.end()) return it->second;
    Texture t;
    t.name = fmt::format("alpha {}", a);
    t.width = t.height = 1;
    t.srgb = false;
    t.rgba = {255, 255, 255, uint8_t(byte)};
    int32_t id = addTexture(std::move(t));
    constantAlpha.emplace(byte, id);
    return id;
  }

  // --------------------------------------------------------------- parameters

  struct Color {
    Vec3f value;
    int32_t texture = kNoTexture;
  };

  static SolidTextureKind solidKind(const std::string& className) {
    if (className == "marble") return SolidTextureKind::Marble;
    if (className == "fbm") return SolidTextureKind::Fbm;
    if (className == "wrinkled") return SolidTextureKind::Wrinkled;
    if (className == "windy") return SolidTextureKind::Windy;
    return SolidTextureKind::None;
  }

  // A solid texture as a Ferry texture, evaluated at the shading point
  // (scene/solid_texture.h).
  Texture solidTextureOf(const PbrtTextureDefinition& t) {
    Texture texture;
    texture.name = t.className + " \"" + t.name + "\"";
    SolidTexture& s = texture.solid;
    s.kind = solidKind(t.className);
    // The texture's space: pbrt-v4's inverse of the CTM at the definition,
    // or pbrt-v3's CTM itself (PbrtTextureDefinition); the two agree for the
    // usual identity, and differ only for transformed textures.
    if (t.transformIsWorldToTexture)
      s.worldToTexture = t.transform;
    else
      s.worldToTexture =
          t.transform.determinant() != 0 ? t.transform.inverse() : Affine3f::identity();
    s.octaves = std::clamp(t.params.getInt("octaves", 8), 0, 32);
    s.omega = t.params.getFloat("roughness", 0.5f);
    s.scale = t.params.getFloat("scale", 1);
    s.variation = t.params.getFloat("variation", 0.2f);
    return texture;
  }

  // Whether `t` is or uses a solid texture: then it is evaluated at the
  // shading point (pointTexture), not baked over uv.
  bool usesSolid(const PbrtTextureDefinition& t, int depth = 0) {
    if (solidKind(t.className) != SolidTextureKind::None) return true;
    if (depth > kMaxDepth) return false;
    auto [known, inserted] = solidUse_.emplace(&t, false);  // false while being decided
    if (!inserted) return known->second;
    bool uses = false;
    for (const PbrtParam& p : t.params.all())
      if (p.type == "texture" && p.strings.size() == 1)
        if (const PbrtTextureDefinition* sub = findTexture(p.strings[0], t.isFloat))
          uses = uses || usesSolid(*sub, depth + 1);
    solidUse_[&t] = uses;
    return uses;
  }

  // A texture that is or uses a solid texture, as one Ferry texture
  // evaluated at the shading point: the solid texture, or a combination
  // whose operands are constants, baked textures (those that use no solid
  // texture) and such textures in turn.
  Texture pointTexture(const PbrtTextureDefinition& t, int depth) {
    if (depth > kMaxDepth)
      throw InputError(t.where, fmt::format("texture \"{}\": textures nested more than {} deep "
                                            "(a texture that uses itself?)",
                                            t.name, kMaxDepth));
    if (solidKind(t.className) != SolidTextureKind::None) return solidTextureOf(t);
    Texture out;
    out.name = t.className + " \"" + t.name + "\"";
    auto operand = [&](int i, const char* name, Vec3f fallback, bool floatContext) {
      TextureOperand& o = out.operands[size_t(i)];
      o.constant = fallback;
      const PbrtParam* p = t.params.find(name);
      if (!p) return;
      if (p->type != "texture") {
        o.constant = colorValue(*p, SpectrumUse::Reflectance);
        return;
      }
      const PbrtTextureDefinition& sub = textureOf(*p, floatContext);
      if (usesSolid(sub)) {
        o.part = int32_t(out.parts.size());
        out.parts.push_back(pointTexture(sub, depth + 1));
      } else if (sub.className == "constant") {
        evaluations_ = 0;
        o.constant = eval(sub, {0.5f, 0.5f}, 0);
      } else {
        o.part = int32_t(out.parts.size());
        out.parts.push_back(bakedColorTexture(sub));
      }
    };
    auto mapped = [&] {
      const Mapping m = mappingOf(t);
      out.mapping = {m.su, m.sv, m.du, m.dv};
    };
    const std::string& c = t.className;
    const bool f = t.isFloat;
    if (c == "scale") {
      out.combination = TextureCombination::Scale;
      if (t.params.has("tex1") || t.params.has("tex2")) {  // v3: tex1 * tex2
        operand(0, "tex1", Vec3f(1), f);
        operand(1, "tex2", Vec3f(1), f);
      } else {  // v4: tex * scale
        operand(0, "tex", Vec3f(1), f);
        operand(1, "scale", Vec3f(1), true);
      }
    } else if (c == "mix" || c == "directionmix") {
      out.combination = TextureCombination::Mix;
      operand(0, "tex1", Vec3f(0), f);
      operand(1, "tex2", Vec3f(1), f);
      out.operands[2].constant = Vec3f(0.5f);
      if (c == "mix")
        operand(2, "amount", Vec3f(0.5f), true);
      else
        warnDirectionMix(t);
    } else if (c == "checkerboard") {
      out.combination = TextureCombination::Checkerboard;
      warnCheckerboard3d(t);
      mapped();
      operand(0, "tex1", Vec3f(1), f);
      operand(1, "tex2", Vec3f(0), f);
    } else if (c == "dots") {
      out.combination = TextureCombination::Dots;
      mapped();
      operand(0, "inside", Vec3f(1), f);
      operand(1, "outside", Vec3f(0), f);
    } else if (c == "bilerp") {
      out.combination = TextureCombination::Bilerp;
      mapped();
      operand(0, "v00", Vec3f(0), f);
      operand(1, "v01", Vec3f(1), f);
      operand(2, "v10", Vec3f(0), f);
      operand(3, "v11", Vec3f(1), f);
    } else {  // constant (of a texture), or a class that cannot hold one
      out.combination = TextureCombination::Scale;
      out.operands[1].constant = Vec3f(1);
      if (c == "constant") {
        operand(0, "value", Vec3f(1), f);
      } else {
        unsupportedClass(t);
        t.params.markAllUsed();
        out.operands[0].constant = Vec3f(0.5f);
      }
    }
    reportUnused(t.params, fmt::format("Texture \"{}\" \"{}\"", t.name, t.className));
    return out;
  }

  // pointTexture(t) in the scene, once per definition.
  int32_t pointTextureId(const PbrtTextureDefinition& t) {
    auto found = pointTextures_.find(&t);
    if (found != pointTextures_.end()) return found->second;
    const int32_t index = addTexture(pointTexture(t, 0));
    pointTextures_.emplace(&t, index);
    return index;
  }

  // pbrt-v3 reads a colour only from a spectrum type (rgb, spectrum, xyz,
  // blackbody) or a texture: a "float" of that name is not read, with a
  // warning, as pbrt-v3 leaves it unused.
  bool v3IgnoresFloat(const PbrtParam& p) {
    if (v4File || (p.type != "float" && p.type != "integer")) return false;
    warnings.once("float colour|" + p.name,
                  fmt::format("{}: \"{}\" is a colour; pbrt-v3 does not read it from a float, "
                              "so neither does Ferry (its default is used)",
                              p.where.toString(), p.declaration()));
    return true;
  }

  Color color(const PbrtParams& params, std::initializer_list<const char*> names, Vec3f fallback) {
    for (const char* name : names) {
      const PbrtParam* p = params.find(name);
      if (!p || v3IgnoresFloat(*p)) continue;
      if (p->type == "texture") {
        const PbrtTextureDefinition& t = textureOf(*p, false);
        if (t.className == "constant") {
          evaluations_ = 0;
          return {eval(t, {0.5f, 0.5f}, 0)};
        }
        if (usesSolid(t)) return {Vec3f(1), pointTextureId(t)};
        return {Vec3f(1), bakeColor(*p)};
      }
      return {colorValue(*p, SpectrumUse::Reflectance)};
    }
    return {fallback};
  }

  float averageTexture(const PbrtParam& p, bool floatContext) {
    const PbrtTextureDefinition& t = textureOf(p, floatContext);
    auto it = averages.find(t.name);
    if (it != averages.end()) return it->second;
    if (t.className != "constant")
      warnings.once("averaged|" + p.name,
                    fmt::format("a texture on \"{}\" is averaged to one value (Ferry's {} is not "
                                "textured; first at {})",
                                p.declaration(), p.name, p.where.toString()));
    double sum = 0;
    evaluations_ = 0;
    if (usesSolid(t)) {
      // Over uv and over points of a cube of space (kAverageSpace a side,
      // Roberts' R3 sequence): solid textures vary in space.
      const Texture point = pointTexture(t, 0);
      const Vec3f step{0.8191725f, 0.6710436f, 0.5497005f};
      for (int i = 0; i < kAverageGrid * kAverageGrid; ++i) {
        const Vec2f uv{(i % kAverageGrid + 0.5f) / kAverageGrid,
                       (i / kAverageGrid + 0.5f) / kAverageGrid};
        Vec3f r = Vec3f(0.5f) + step * float(i);
        r = r - Vec3f(std::floor(r.x), std::floor(r.y), std::floor(r.z));
        sum += average(point.value(uv, r * kAverageSpace));
      }
    } else {
      for (int y = 0; y < kAverageGrid; ++y)
        for (int x = 0; x < kAverageGrid; ++x)
          sum += average(eval(t, {(x + 0.5f) / kAverageGrid, (y + 0.5f) / kAverageGrid}, 0));
    }
    float value = float(sum / (kAverageGrid * kAverageGrid));
    averages.emplace(t.name, value);
    return value;
  }

  // A colour that Ferry does not texture (a coat's tint): a texture is averaged.
  Vec3f untexturedColor(const PbrtParams& params, const char* name, Vec3f fallback) {
    const PbrtParam* p = params.find(name);
    if (!p || v3IgnoresFloat(*p)) return fallback;
    if (p->type == "texture") return Vec3f(averageTexture(*p, false));
    return colorValue(*p, SpectrumUse::Reflectance);
  }

  float scalar(const PbrtParams& params, const char* name, float fallback) {
    const PbrtParam* p = params.find(name);
    if (!p) return fallback;
    if (p->type == "texture") return averageTexture(*p, true);
    if (p->type == "float" || p->type == "integer") return params.getFloat(name, fallback);
    const Vec3f c = colorValue(*p, SpectrumUse::Reflectance);
    if (!(c.x == c.y && c.y == c.z))
      warnings.once("grey|" + std::string(name),
                    fmt::format("{}: a colour where Ferry takes one number: its average is used",
                                p->declaration()));
    return average(c);
  }

  // Which roughness parameters a pbrt model reads: "roughness" with
  // uroughness/vroughness overriding it (pbrt-v4's, v3's metal and uber),
  // only uroughness/vroughness (v3's glass and substrate) or only
  // "roughness" (v3's plastic and translucent). The others are left unread,
  // so they are reported as unused.
  enum class RoughnessNames { Both, UV, Scalar };

  // Ferry roughness from pbrt's roughness, uroughness/vroughness and remaproughness.
  // `zeroIsSmooth`: roughness 0 in both directions is a smooth (specular)
  // surface before any remapping, as pbrt-v3's glass tests it; pbrt-v3's other
  // models remap 0 to a small alpha (about 0.05).
  float roughness(const PbrtParams& params, const std::string& prefix, float fallback, bool v3,
                  bool zeroIsSmooth = false, RoughnessNames names = RoughnessNames::Both) {
    std::string un = prefix + "uroughness", vn = prefix + "vroughness", rn = prefix + "roughness";
    const float r = names == RoughnessNames::UV ? fallback : scalar(params, rn.c_str(), fallback);
    const float u = names == RoughnessNames::Scalar ? r : scalar(params, un.c_str(), r);
    const float v = names == RoughnessNames::Scalar ? r : scalar(params, vn.c_str(), r);
    if (zeroIsSmooth && u == 0 && v == 0) return 0;
    bool remap = params.getBool("remaproughness", true);
    auto alpha = [&](float x) {
      x = std::max(x, 0.0f);
      if (!remap) return x;
      return v3 ? std::max(v3RoughnessToAlpha(x), 0.0f) : std::sqrt(x);
    };
    float a = std::sqrt(alpha(u) * alpha(v));
    return std::clamp(std::sqrt(a), 0.0f, 1.0f);
  }

  // pbrt-v4's layered parameters: the interface's width (`interfacePrefix`),
  // the conductor base's (`conductorPrefix`, empty for a diffuse base), the
  // slab (thickness, albedo, g) and the walk (maxdepth, nsamples).
  std::shared_ptr<LayeredModel> layeredModel(const PbrtParams& p,
                                             const std::string& interfacePrefix,
                                             const std::string& conductorPrefix) {
    auto layered = std::make_shared<LayeredModel>();
    const float r = roughness(p, interfacePrefix, 0.0f, false);
    layered->alpha = r * r;
    if (!conductorPrefix.empty()) {
      const float base = roughness(p, conductorPrefix, 0.0f, false);
      layered->conductorBase = true;
      layered->baseAlpha = base * base;
    }
    layered->thickness = std::max(scalar(p, "thickness", 0.01f), 0.0f);
    layered->albedo = max(untexturedColor(p, "albedo", Vec3f(0)), Vec3f(0));
    layered->g = std::clamp(scalar(p, "g", 0.0f), -0.99f, 0.99f);
    layered->maxDepth = std::clamp(p.getInt("maxdepth", 10), 1, 1000);
    layered->samples = std::clamp(p.getInt("nsamples", 1), 1, 1000);
    return layered;
  }

  float iorOf(const PbrtParams& params, float fallback) {
    for (const char* name : {"eta", "index"}) {
      const PbrtParam* p = params.find(name);
      if (!p) continue;
      if (p->type == "texture") return averageTexture(*p, true);
      if (p->type == "spectrum") return spectrumOf(*p).at(550);
      if (p->type == "float") return params.getFloat(name, fallback);
      PbrtParams::fail(*p, "expected a float or a spectrum");
    }
    return fallback;
  }

  // `outside`: the index of the medium the conductor is under (a coat's).
  Vec3f conductorColor(const PbrtParams& params, const std::string& prefix, float outside = 1) {
    std::string etaName = prefix + "eta", kName = prefix + "k";
    const PbrtParam* eta = params.find(etaName);
    const PbrtParam* k = params.find(kName);
    auto texture = [&](const PbrtParam* p) {
      if (p && p->type == "texture") {
        warnings.once("conductor texture",
                      fmt::format("textured \"{}\" is not supported; using copper's (first at {})",
                                  p->declaration(), p->where.toString()));
        return true;
      }
      return false;
    };
    if (texture(eta)) eta = nullptr;
    if (texture(k)) k = nullptr;
    bool spectral = (!eta || eta->type == "spectrum") && (!k || k->type == "spectrum");
    if (spectral) {
      SampledSpectrum se = eta ? spectrumOf(*eta) : *namedSpectrum("metal-Cu-eta");
      SampledSpectrum sk = k ? spectrumOf(*k) : *namedSpectrum("metal-Cu-k");
      return conductorReflectance(se, sk, outside);
    }
    Vec3f e = (eta ? perChannel(*eta) : Vec3f(0.2f, 0.92f, 1.1f)) / outside;
    Vec3f kk = (k ? perChannel(*k) : Vec3f(3.9f, 2.45f, 2.14f)) / outside;
    Vec3f f0;
    for (int c = 0; c < 3; ++c)
      f0[c] = ((e[c] - 1) * (e[c] - 1) + kk[c] * kk[c]) / ((e[c] + 1) * (e[c] + 1) + kk[c] * kk[c]);
    return min(max(f0, Vec3f(0)), Vec3f(1));
  }

  // ---------------------------------------------------------------- materials

  void layerWarning(const std::string& type, const SourceLocation& where, const char* what) {
    warnings.once("layer|" + type, fmt::format("material \"{}\": {} is not modelled (Ferry's "
                                               "materials do not have it); first at {}",
                                               type, what, where.toString()));
  }

  void consume(const PbrtParams& params, std::initializer_list<const char*> names) {
    for (const char* n : names) params.find(n);
  }

  // Definition `id` as a scene material of its own (once), for a mix to
  // switch to.
  int32_t mixTarget(int32_t id, int depth) {
    auto found = mixTargets.find(id);
    if (found != mixTargets.end()) return found->second;
    const int32_t index = scene.addMaterial(convert(id, depth).m);
    mixTargets.emplace(id, index);
    return index;
  }

  Look convert(int32_t id, int depth) {
    if (id < 0) {
      Look look;
      look.m.name = "default";
      look.m.baseColor = Vec3f(0.5f);
      return look;
    }
    if (looks[size_t(id)]) return *looks[size_t(id)];
    const PbrtMaterialDefinition& def = definitions[size_t(id)];
    if (converting[size_t(id)] || depth > kMaxDepth)
      throw InputError(def.where, fmt::format("material \"{}\" mixes itself", def.name));
    converting[size_t(id)] = 1;
    Look look = convertDefinition(def, depth);
    converting[size_t(id)] = 0;
    look.m.name = def.name.empty() ? def.type : def.name;
    reportUnused(def.params, fmt::format("material \"{}\"", def.type));
    looks[size_t(id)] = look;
    return look;
  }

  // pbrt's subsurface and kdsubsurface: a dielectric surface (its model in
  // `m`) over the homogeneous medium returned, walked through
  // (material/models/subsurface.h). The medium is sigma_a and sigma_s times
  // scale: named (pbrt's measured media, g then 0), given, or (kdsubsurface's
  // Kd, pbrt-v4's reflectance) inverted through the photon beam diffusion
  // profile with extinction 1 / (scale mfp). pbrt-v3 is told from pbrt-v4 by
  // the file (v4File) or by v4's names ("reflectance", "roughness").
  Medium subsurface(const PbrtParams& p, const PbrtMaterialDefinition& def, Material& m) {
    const bool v3 =
        def.type == "kdsubsurface" || !(v4File || p.has("reflectance") || p.has("roughness"));
    const float eta = std::max(scalar(p, "eta", 1.33f), 1.01f);
    float g = std::clamp(scalar(p, "g", 0.0f), -0.99f, 0.99f);
    const float scale = scalar(p, "scale", 1.0f);
    Vec3f sigmaA{0.0011f, 0.0024f, 0.014f}, sigmaS{2.55f, 3.21f, 3.77f};
    const std::string name = p.getString("name", "");
    const bool fromReflectance =
        def.type == "kdsubsurface" ||
        (!v3 && name.empty() && !p.has("sigma_a") && !p.has("sigma_s") && p.has("reflectance"));
    if (fromReflectance) {
      const Vec3f reflectance = min(
          max(untexturedColor(p, def.type == "kdsubsurface" ? "Kd" : "reflectance", Vec3f(0.5f)),
              Vec3f(0)),
          Vec3f(1));
      const Vec3f mfp = untexturedColor(p, "mfp", Vec3f(1)) * scale;
      if (!(std::min({mfp.x, mfp.y, mfp.z}) > 0))
        throw InputError(def.where,
                         fmt::format("{}: \"mfp\" times \"scale\" must be positive", def.type));
      const Vec3f albedo = subsurfaceAlbedoFromReflectance(reflectance, g, eta);
      const Vec3f sigmaT{1 / mfp.x, 1 / mfp.y, 1 / mfp.z};
      sigmaS = albedo * sigmaT;
      sigmaA = sigmaT - sigmaS;
    } else {
      if (!name.empty()) {
        if (!mediumPreset(name, sigmaA, sigmaS)) {
          if (!v3)
            throw InputError(def.where,
                             fmt::format("subsurface: no measured medium named \"{}\"", name));
          warnings.once("subsurface name|" + name,
                        fmt::format("{}: subsurface: no measured medium named \"{}\"; its "
                                    "defaults are used (as pbrt-v3 does)",
                                    def.where.toString(), name));
        } else {
          g = 0;  // pbrt: the measurements are reduced scattering coefficients
        }
      }
      // pbrt-v3 lets sigma_a and sigma_s override a name; pbrt-v4 does not.
      if (v3 || name.empty()) {
        sigmaA = untexturedColor(p, "sigma_a", sigmaA);
        sigmaS = untexturedColor(p, "sigma_s", sigmaS);
      }
      sigmaA = max(sigmaA, Vec3f(0)) * scale;
      sigmaS = max(sigmaS, Vec3f(0)) * scale;
    }
    if (!isFinite(sigmaA) || !isFinite(sigmaS) || !(maxComponent(sigmaA + sigmaS) > 0))
      throw InputError(def.where, fmt::format("{}: its medium must have a finite, positive "
                                              "extinction",
                                              def.type));
    const float rough = roughness(p, "", 0.0f, v3, /*zeroIsSmooth=*/true,
                                  v3 ? RoughnessNames::UV : RoughnessNames::Both);
    Vec3f reflectTint{1};
    if (v3) {
      reflectTint = min(max(untexturedColor(p, "Kr", Vec3f(1)), Vec3f(0)), Vec3f(1));
      const Color kt = color(p, {"Kt"}, Vec3f(1));
      m.baseColor = kt.value;
      m.baseColorTexture = kt.texture;
    } else {
      m.baseColor = Vec3f(1);
    }
    // The definition is what pbrt's material object is: its index is the probe id.
    m.model = std::make_shared<SubsurfaceModel>(eta, rough, reflectTint, sigmaA, sigmaS, g,
                                                uint32_t(&def - definitions.data()));
    Medium medium;
    medium.name = (def.name.empty() ? def.type : def.name) + " (inside)";
    medium.sigmaA = sigmaA;
    medium.sigmaS = sigmaS;
    medium.g = g;
    medium.subsurface = true;
    return medium;
  }

  // pbrt-v3's fourier material: its "bsdffile" read once per path into
  // Scene::bsdfTables. A file that is not there is a warning naming it (the
  // material then renders grey diffuse); a file that is there but malformed
  // is an error naming it and where it is named.
  bool fourierTable(const PbrtParams& p, const PbrtMaterialDefinition& def, Material& m) {
    const PbrtParam* file = p.find("bsdffile");
    const std::string name = p.getString("bsdffile", "");
    const SourceLocation& where = file ? file->where : def.where;
    std::string path;
    try {
      if (name.empty()) throw InputError(where, "no \"string bsdffile\"");
      path = resolve(name, where);
    } catch (const InputError& e) {
      warnings.once("fourier|" + name,
                    fmt::format("fourier material: {}; rendered as diffuse (0.5, 0.5, 0.5) "
                                "instead",
                                e.what()));
      return false;
    }
    auto it = bsdfTables.find(path);
    if (it == bsdfTables.end()) {
      std::shared_ptr<const FourierBsdfTable> table;
      try {
        table = readFourierBsdfFile(path);
      } catch (const InputError& e) {
        throw InputError(where, fmt::format("\"string bsdffile\": {}", e.what()));
      }
      scene.bsdfTables.push_back(std::move(table));
      it = bsdfTables.emplace(path, int32_t(scene.bsdfTables.size() - 1)).first;
    }
    m.model = std::make_shared<FourierModel>(it->second);
    m.baseColor = Vec3f(0.5f);  // (unused by the table; what a viewer of the material sees)
    return true;
  }

  Look convertDefinition(const PbrtMaterialDefinition& def, int depth) {
    const PbrtParams& p = def.params;
    const std::string& type = def.type;
    const bool v3 = isV3Material(type);
    Look look;
    Material& m = look.m;
    auto setColor = [&](const Color& c) {
      m.baseColor = c.value;
      m.baseColorTexture = c.texture;
    };
    // pbrt-v3's "bumpmap", pbrt-v4's "displacement": a float texture.
    for (const char* name : {"bumpmap", "displacement"})
      if (const PbrtParam* bump = p.find(name)) {
        if (bump->type != "texture") PbrtParams::fail(*bump, "expected a float texture");
        m.bumpTexture = bakeBump(*bump, m.bumpScale);
      }
    if (type == "diffuse" || type == "matte") {
      setColor(color(p, {"reflectance", "Kd"}, Vec3f(0.5f)));
      if (type == "matte")
        m.model = std::make_shared<DiffuseModel>(std::clamp(scalar(p, "sigma", 0), 0.0f, 90.0f));
    } else if (type == "translucent") {
      // pbrt-v3: Kd reflected (times "reflect") and transmitted (times
      // "transmit") diffusely, plus Ks's glossy reflection and transmission,
      // which Ferry drops.
      const Vec3f reflect = untexturedColor(p, "reflect", Vec3f(0.5f));
      const Vec3f transmit = untexturedColor(p, "transmit", Vec3f(0.5f));
      Color kd = color(p, {"Kd"}, Vec3f(0.25f));
      setColor({kd.value * reflect, kd.texture});
      m.model = std::make_shared<DiffuseTransmissionModel>(untexturedColor(p, "Kd", Vec3f(0.25f)) *
                                                           transmit);
      if (maxComponent(untexturedColor(p, "Ks", Vec3f(0.25f))) > 0)
        layerWarning(type, def.where, "the glossy part (Ks)");
      consume(p, {"roughness", "remaproughness"});
    } else if (type == "diffusetransmission") {
      // pbrt-v4: Lambertian reflection and transmission, both times scale.
      const float s = p.getFloat("scale", 1);
      Color r = color(p, {"reflectance"}, Vec3f(0.25f));
      setColor({r.value * s, r.texture});
      m.model = std::make_shared<DiffuseTransmissionModel>(
          untexturedColor(p, "transmittance", Vec3f(0.25f)) * s);
    } else if (type == "plastic") {
      // pbrt-v3: Lambertian Kd plus a Trowbridge-Reitz reflection of Ks with
      // FresnelDielectric(1.5, 1), i.e. seen from inside the glass: Ferry's
      // eta (n_t / n_i) is 1 / 1.5, which totally reflects microfacets met
      // beyond 41.8 degrees. That is pbrt-v3's plastic (its reference images
      // have it), so Ferry keeps it.
      setColor(color(p, {"Kd"}, Vec3f(0.25f)));
      auto plastic = std::make_shared<CoatedDiffuseModel>();
      plastic->specular = untexturedColor(p, "Ks", Vec3f(0.25f));
      plastic->roughness = roughness(p, "", 0.1f, true, false, RoughnessNames::Scalar);
      plastic->eta = 1 / 1.5f;
      plastic->layered = false;
      m.model = plastic;
    } else if (type == "substrate") {
      // pbrt-v3's FresnelBlend (Ashikhmin-Shirley).
      setColor(color(p, {"Kd"}, Vec3f(0.5f)));
      auto substrate = std::make_shared<FresnelBlendModel>();
      substrate->specular = untexturedColor(p, "Ks", Vec3f(0.5f));
      substrate->roughness = roughness(p, "", 0.1f, true, false, RoughnessNames::UV);
      m.model = substrate;
    } else if (type == "coateddiffuse") {
      // pbrt-v4: a diffuse base under a dielectric interface, a random walk
      // between them (material/models/layered.h).
      setColor(color(p, {"reflectance"}, Vec3f(0.5f)));
      auto layered = layeredModel(p, "", "");
      layered->eta = std::max(iorOf(p, 1.5f), 1.01f);
      m.model = layered;
    } else if (type == "conductor" || type == "metal") {
      if (p.has("reflectance")) {
        setColor(color(p, {"reflectance"}, Vec3f(1)));
      } else {
        m.baseColor = conductorColor(p, "");
      }
      const float baseRoughness = roughness(p, "", type == "metal" ? 0.01f : 0.0f, v3);
      m.model = std::make_shared<ConductorModel>(baseRoughness);
    } else if (type == "coatedconductor") {
      // pbrt-v4: the conductor under a dielectric interface, a random walk
      // between them (material/models/layered.h). The conductor is seen from
      // inside the coat: its eta and k relative to the coat's index.
      auto layered = layeredModel(p, "interface.", "conductor.");
      layered->eta = 1.5f;
      if (const PbrtParam* eta = p.find("interface.eta")) {
        if (eta->type == "spectrum")
          layered->eta = spectrumOf(*eta).at(550);
        else
          layered->eta = p.getFloat("interface.eta", 1.5f);
      }
      layered->eta = std::max(layered->eta, 1.01f);
      if (p.has("reflectance")) {
        setColor(color(p, {"reflectance"}, Vec3f(1)));
      } else {
        m.baseColor = conductorColor(p, "conductor.", layered->eta);
      }
      m.model = layered;
    } else if (type == "mirror") {
      setColor(color(p, {"Kr"}, Vec3f(0.9f)));
      m.model = std::make_shared<ConductorModel>(0.0f);
    } else if (type == "dielectric" || type == "glass" || type == "thindielectric") {
      m.baseColor = Vec3f(1);
      if (type == "glass") setColor(color(p, {"Kt"}, Vec3f(1)));
      float ior = iorOf(p, 1.5f);
      if (!(ior >= 1)) ior = std::max(1.0f / std::max(ior, 1e-3f), 1.01f);
      if (type == "thindielectric") {
        m.model = std::make_shared<ThinDielectricModel>(ior);
      } else {
        const float rough = type == "glass" ? roughness(p, "", 0.0f, true, /*zeroIsSmooth=*/true,
                                                        RoughnessNames::UV)
                                            : roughness(p, "", 0.0f, v3);
        m.model = std::make_shared<DielectricModel>(ior, rough);
      }
    } else if (type == "uber") {
      // pbrt-v3: Kd (Lambertian) + Ks (Trowbridge-Reitz, FresnelDielectric(1,
      // eta)) + Kr (mirror) + Kt (window), with opacity.
      Color kd = color(p, {"Kd"}, Vec3f(0.25f));
      Color kr = color(p, {"Kr"}, Vec3f(0));
      Color kt = color(p, {"Kt"}, Vec3f(0));
      const Vec3f ks = untexturedColor(p, "Ks", Vec3f(0.25f));
      float rough = roughness(p, "", 0.1f, true);
      float ior = iorOf(p, 1.5f);
      Color opacity = color(p, {"opacity"}, Vec3f(1));
      // Ferry's uber is one of its lobes: the window when Kt reaches 0.5, else
      // the mirror when Kr outweighs Kd, else Kd under the Ks coat. What that
      // leaves out is said once.
      if (maxComponent(kt.value) >= 0.5f) {
        setColor(kt);
        m.model = std::make_shared<DielectricModel>(std::max(ior, 1.01f), rough);
        if (maxComponent(kd.value) > 0 || maxComponent(ks) > 0 || maxComponent(kr.value) > 0)
          layerWarning(type, def.where, "Kd, Ks and Kr beside a Kt of 0.5 or more");
      } else if (maxComponent(kr.value) > maxComponent(kd.value)) {
        setColor(kr);
        m.model = std::make_shared<ConductorModel>(0.0f);
        if (maxComponent(kd.value) > 0 || maxComponent(ks) > 0 || maxComponent(kt.value) > 0)
          layerWarning(type, def.where, "Kd, Ks and Kt beside a Kr that outweighs Kd");
      } else {
        if (maxComponent(kt.value) > 0) layerWarning(type, def.where, "a Kt below 0.5");
        setColor(kd);
        auto coated = std::make_shared<CoatedDiffuseModel>();
        coated->specular = ks;
        coated->roughness = rough;
        coated->eta = std::max(ior, 1.01f);
        coated->layered = false;
        m.model = coated;
        if (maxComponent(kr.value) > 0) layerWarning(type, def.where, "the mirror layer (Kr)");
      }
      // pbrt-v3's uber passes 1 - opacity of the light straight through (a
      // specular transmission of index 1): in expectation a stochastic
      // cut-out for paths; shadow rays, which see no materials, it stops.
      if (opacity.texture == kNoTexture && average(opacity.value) < 1)
        look.alpha = {alphaConstant(std::max(average(opacity.value), 0.0f)), AlphaTest::Stochastic,
                      AlphaRays::NotShadowRays};
      if (opacity.texture != kNoTexture) layerWarning(type, def.where, "a textured opacity");
    } else if (type == "disney") {
      setColor(color(p, {"color"}, Vec3f(0.5f)));
      MetallicRoughness surface;
      surface.metallic = std::clamp(scalar(p, "metallic", 0), 0.0f, 1.0f);
      surface.roughness = std::clamp(scalar(p, "roughness", 0.5f), 0.0f, 1.0f);
      surface.transmission = std::clamp(scalar(p, "spectrans", 0), 0.0f, 1.0f);
      surface.ior = std::max(iorOf(p, 1.5f), 1.01f);
      m.model = modelOf(surface);
    } else if (type == "mix") {
      std::string first, second;
      bool v4 = false;
      if (const PbrtParam* list = p.getArray("materials", {"string"})) {
        if (list->strings.size() != 2) PbrtParams::fail(*list, "expected two material names");
        first = list->strings[0];
        second = list->strings[1];
        v4 = true;
      } else {
        first = p.getString("namedmaterial1", "");
        second = p.getString("namedmaterial2", "");
      }
      float amount = scalar(p, "amount", 0.5f);
      auto sub = [&](const std::string& name) {
        auto it = named.find(name);
        if (it == named.end())
          throw InputError(def.where, fmt::format("mix material: no material named \"{}\"", name));
        return convert(it->second, depth + 1);
      };
      // A mix shades each point with one of the two (render/path_shading:
      // the second with probability wb): pbrt-v4 picks one by a hash, and
      // in expectation that is pbrt-v3's weighted sum of the two BSDFs.
      const Look a = sub(first), b = sub(second);  // (both must exist)
      // v3's amount weighs the first material, v4's the second.
      const float wb = std::clamp(v4 ? amount : 1 - amount, 0.0f, 1.0f);
      m = a.m;
      m.mixedWith = mixTarget(named.at(second), depth + 1);
      m.mixAmount = wb;
      look.alpha = wb > 0.5f ? b.alpha : a.alpha;
    } else if (type == "hair") {
      // pbrt-v3 and v4: sigma_a, else a colour (v3 "color", v4
      // "reflectance"), else melanin (eumelanin 1.3 when nothing is given).
      auto hair = std::make_shared<HairModel>();
      hair->eta = scalar(p, "eta", 1.55f);
      hair->betaM = scalar(p, "beta_m", 0.3f);
      hair->betaN = scalar(p, "beta_n", 0.3f);
      hair->alphaDegrees = scalar(p, "alpha", 2.0f);
      const char* colorName = p.find("color") ? "color" : "reflectance";
      auto ignored = [&](std::initializer_list<const char*> names, const char* because) {
        for (const char* name : names)
          if (const PbrtParam* q = p.find(name))
            warnings.once("hair|" + std::string(name),
                          fmt::format("{}: ignored since \"{}\" is given (as pbrt does)",
                                      q->declaration(), because));
      };
      if (p.find("sigma_a")) {
        hair->absorption = HairModel::Absorption::SigmaA;
        hair->sigmaA = untexturedColor(p, "sigma_a", Vec3f(0));
        ignored({"color", "reflectance", "eumelanin", "pheomelanin"}, "sigma_a");
      } else if (p.find(colorName)) {
        hair->absorption = HairModel::Absorption::Color;
        setColor(color(p, {colorName}, Vec3f(0.5f)));
        ignored({"eumelanin", "pheomelanin"}, colorName);
      } else if (p.find("eumelanin") || p.find("pheomelanin")) {
        hair->eumelanin = scalar(p, "eumelanin", 0);
        hair->pheomelanin = scalar(p, "pheomelanin", 0);
      }
      m.model = hair;
    } else if (type == "subsurface" || type == "kdsubsurface") {
      look.interior = subsurface(p, def, m);
    } else if (type == "fourier" && fourierTable(p, def, m)) {
      // (m's model reads the table; a file that is not there falls through to
      // the grey diffuse below, with a warning naming it.)
    } else if (type == "interface" || type == "none" || type.empty()) {
      look.alpha = {alphaConstant(0), AlphaTest::Below, AlphaRays::All};
    } else {
      Color c{Vec3f(0.5f)};
      for (const char* name : {"reflectance", "Kd", "color"}) {
        const PbrtParam* q = p.find(name);
        if (q && q->type != "texture") {
          c = {colorValue(*q, SpectrumUse::Reflectance)};
          break;
        }
      }
      setColor(c);
      p.markAllUsed();
      // (A fourier material whose table is not there was warned about, naming the file.)
      if (type != "fourier")
        warnings.once(
            "material|" + type,
            fmt::format("material type \"{}\" is not supported: rendered as diffuse ({:.2g}, "
                        "{:.2g}, {:.2g}) instead (first at {})",
                        type, c.value.x, c.value.y, c.value.z, def.where.toString()));
    }
    m.baseColor = min(max(m.baseColor, Vec3f(0)), Vec3f(1));
    return look;
  }
};

PbrtMaterials::PbrtMaterials(Scene& scene, LoadWarnings& warnings, Resolver resolve)
    : impl_(std::make_unique<Impl>(scene, warnings, std::move(resolve))) {}

PbrtMaterials::~PbrtMaterials() = default;

void PbrtMaterials::defineTexture(PbrtTextureDefinition definition) {
  auto& map = definition.isFloat ? impl_->floatTextures : impl_->colorTextures;
  auto it = map.find(definition.name);
  if (it != map.end()) {
    impl_->warnings.once(
        "texture redefined|" + definition.name,
        fmt::format("{}: texture \"{}\" redefined (first at {}); the new one "
                    "applies from here",
                    definition.where.toString(), definition.name, it->second.where.toString()));
    // Shapes that already baked the old one keep it.
    impl_->bakedColor.erase(definition.name);
    impl_->bakedAlpha.erase(definition.name);
    impl_->averages.erase(definition.name);
    it->second = std::move(definition);
    return;
  }
  std::string name = definition.name;
  map.emplace(name, std::move(definition));
}

int32_t PbrtMaterials::addMaterial(PbrtMaterialDefinition definition) {
  impl_->definitions.push_back(std::move(definition));
  impl_->looks.emplace_back();
  impl_->converting.push_back(0);
  return int32_t(impl_->definitions.size() - 1);
}

void PbrtMaterials::nameMaterial(const std::string& name, int32_t definition) {
  auto [it, inserted] = impl_->named.try_emplace(name, definition);
  if (!inserted) {
    const auto& def = impl_->definitions[size_t(definition)];
    impl_->warnings.once("material redefined|" + name,
                         fmt::format("{}: named material \"{}\" redefined; the new one applies "
                                     "from here",
                                     def.where.toString(), name));
    it->second = definition;
  }
}

std::optional<int32_t> PbrtMaterials::namedMaterial(const std::string& name) const {
  auto it = impl_->named.find(name);
  if (it == impl_->named.end()) return std::nullopt;
  return it->second;
}

int32_t PbrtMaterials::materialFor(int32_t definition, Vec3f emission, PbrtAlpha alpha,
                                   bool emitsBackSide, bool lightSampledOnBackSide) {
  auto key = std::make_tuple(definition, emission.x, emission.y, emission.z, alpha.texture,
                             alpha.test, alpha.rays, emitsBackSide, lightSampledOnBackSide);
  auto it = impl_->ferryMaterials.find(key);
  if (it != impl_->ferryMaterials.end()) return it->second;
  Look look = impl_->convert(definition, 0);
  Material m = look.m;
  m.emission = emission;
  m.emitsBackSide = emitsBackSide;
  m.lightSampledOnBackSide = lightSampledOnBackSide;
  const PbrtAlpha& cut = look.alpha.texture != kNoTexture ? look.alpha : alpha;
  m.alphaTexture = cut.texture;
  m.alphaTest = cut.test;
  m.alphaRays = cut.rays;
  if (m.isEmissive()) m.name += " (emitting)";
  int32_t index = impl_->scene.addMaterial(std::move(m));
  impl_->ferryMaterials.emplace(key, index);
  if (look.interior) {
    impl_->scene.media.push_back(*look.interior);
    impl_->interiors.emplace(index, int32_t(impl_->scene.media.size() - 1));
  }
  return index;
}

int32_t PbrtMaterials::interiorMedium(int32_t material) const {
  auto it = impl_->interiors.find(material);
  return it == impl_->interiors.end() ? kNoMedium : it->second;
}

void PbrtMaterials::setV4File(bool v4) {
  impl_->v4File = v4;
}

bool PbrtMaterials::isInterface(int32_t definition) const {
  if (definition < 0) return false;
  const std::string& type = impl_->definitions[size_t(definition)].type;
  return type == "interface" || type == "none" || type.empty();
}

PbrtAlpha PbrtMaterials::shapeAlpha(const PbrtParams& shape, bool v3) {
  if (!v3) {
    const PbrtParam* p = shape.find("alpha");
    if (!p) return {};
    int32_t texture;
    if (p->type == "texture") {
      texture = impl_->bakeAlpha(*p);
    } else {
      const float a = shape.getFloat("alpha", 1);
      if (a >= 1) return {};
      texture = impl_->alphaConstant(std::max(a, 0.0f));
    }
    return {texture, AlphaTest::Stochastic, AlphaRays::All};
  }
  auto one = [&](const char* name) {
    const PbrtParam* p = shape.find(name);
    if (!p) return kNoTexture;
    if (p->type == "texture") return impl_->bakeAlpha(*p);
    return shape.getFloat(name, 1) == 0 ? impl_->alphaConstant(0) : kNoTexture;
  };
  const int32_t paths = one("alpha"), shadows = one("shadowalpha");
  if (paths == kNoTexture && shadows == kNoTexture) return {};
  if (paths == kNoTexture) return {shadows, AlphaTest::Zero, AlphaRays::ShadowRaysOnly};
  if (shadows == kNoTexture) return {paths, AlphaTest::Zero, AlphaRays::NotShadowRays};
  if (paths != shadows)
    impl_->warnings.once("shadowalpha",
                         fmt::format("\"shadowalpha\" differs from \"alpha\": Ferry cuts "
                                     "shadow rays by \"alpha\" too (first at {})",
                                     shape.find("shadowalpha")->where.toString()));
  return {paths, AlphaTest::Zero, AlphaRays::All};
}

Vec3f PbrtMaterials::constantColor(const PbrtParams& params, const std::string& name,
                                   Vec3f fallback, SpectrumUse use) {
  const PbrtParam* p = params.find(name);
  if (!p) return fallback;
  if (p->type == "texture") PbrtParams::fail(*p, "a light's colour cannot be a texture");
  return impl_->colorValue(*p, use);
}

}  // namespace ferry
