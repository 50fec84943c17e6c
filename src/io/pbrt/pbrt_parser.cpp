#include "io/pbrt/pbrt_parser.h"

#include "scene/mesh_store.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>

#include <fmt/format.h>

#include "core/error.h"
#include "io/images/image_io.h"
#include "io/pbrt/pbrt_materials.h"
#include "io/pbrt/pbrt_params.h"
#include "io/pbrt/pbrt_spectra.h"
#include "io/pbrt/pbrt_tokenizer.h"
#include "io/ply/ply_reader.h"
#include "io/shape_tessellation.h"
#include "io/volumes/volume_files.h"
#include "media/medium_presets.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

constexpr int kMaxIncludeDepth = 64;
constexpr int kMaxFilmSide = 16384;
// Media emitting by temperature look the blackbody's RGB up every 10 K up to 40000 K.
constexpr size_t kBlackbodyEntries = 4001;
constexpr float kBlackbodyStep = 10;

float radians(float degrees) {
  return degrees * kPi / 180.0f;
}

bool sameTransform(const Affine3f& a, const Affine3f& b) {
  return std::memcmp(&a, &b, sizeof(Affine3f)) == 0;
}

// Clarberg's equal-area mapping of the sphere to the unit square (pbrt-v4's
// environment maps), u along x, v along y.
Vec2f equalAreaSphereToSquare(Vec3f d) {
  float x = std::abs(d.x), y = std::abs(d.y), z = std::abs(d.z);
  float r = std::sqrt(std::max(0.0f, 1 - z));
  float a = std::max(x, y), b = std::min(x, y);
  b = a == 0 ? 0 : b / a;
  float phi = std::atan(b) * 2 / kPi;
  if (x < y) phi = 1 - phi;
  float v = phi * r;
  float u = r - v;
  if (d.z < 0) {
    std::swap(u, v);
    u = 1 - u;
    v = 1 - v;
  }
  u = std::copysign(u, d.x);
  v = std::copysign(v, d.y);
  return {0.5f * (u + 1), 0.5f * (v + 1)};
}

Vec3f bilinear(const HdrImage& img, float x, float y, bool wrapX) {
  float fx = std::floor(x), fy = std::floor(y);
  float tx = x - fx, ty = y - fy;
  auto at = [&](long ix, long iy) {
    if (wrapX)
      ix = ((ix % img.width) + img.width) % img.width;
    else
      ix = std::clamp<long>(ix, 0, img.width - 1);
    iy = std::clamp<long>(iy, 0, img.height - 1);
    return img.at(int(ix), int(iy));
  };
  long ix = long(fx), iy = long(fy);
  return lerp(lerp(at(ix, iy), at(ix + 1, iy), tx), lerp(at(ix, iy + 1), at(ix + 1, iy + 1), tx),
              ty);
}

struct AreaLight {
  Vec3f radiance;
  bool twoSided = false;  // pbrt's "bool twosided" (default: only the front emits)
  // pbrt-v4's "float power": the radiance is scaled so that each pbrt shape
  // it lights emits this many watts (applied per shape, with its area).
  std::optional<float> power;
};

struct GraphicsState {
  Affine3f ctm;     // the current transform at the start time
  Affine3f ctmEnd;  // and at the end time (pbrt's ActiveTransform): equal unless it moves
  bool reverseOrientation = false;
  int32_t material = -1;  // definition id; -1: pbrt's default diffuse
  std::optional<AreaLight> areaLight;
  // MediumInterface: the named media inside and outside the shapes that
  // follow ("": vacuum); the camera is in the outside one.
  std::string mediumInside, mediumOutside;
  std::map<std::string, PbrtParams> attributes;  // v4 `Attribute` defaults by target
};

enum class BlockKind { Attribute, Transform, Object, Import };

const char* blockName(BlockKind k) {
  switch (k) {
    case BlockKind::Attribute:
      return "AttributeBegin";
    case BlockKind::Transform:
      return "TransformBegin";
    case BlockKind::Object:
      return "ObjectBegin";
    case BlockKind::Import:
      return "Import";
  }
  return "";
}

struct Block {
  BlockKind kind;
  GraphicsState saved;
  SourceLocation where;
};

struct CameraDefinition {
  Affine3f cameraFromWorld;
  std::shared_ptr<const InstanceMotion> motion;  // world from camera, when it moves
  float shutterOpen = 0, shutterClose = 1;
  float fov = 90;
  float lensRadius = 0, focalDistance = 1e6f;  // camera space
  SourceLocation where;
};

struct InfiniteLight {
  PbrtParams params;
  Affine3f lightFromWorld;
  SourceLocation where;
};

class Parser {
 public:
  // Which pbrt wrote the file, from the first directive only one of them
  // knows (noteDialect); Unknown is read as pbrt-v4.
  enum class Dialect { Unknown, V3, V4 };

  Parser(std::string mainDirectory, const LoadOptions& options)
      : options_(options),
        warnings_(options),
        mainDirectory_(std::move(mainDirectory)),
        materials_(scene_, warnings_, [this](const std::string& name, const SourceLocation& where) {
          return resolve(name, where, "file");
        }) {}

  void pushFile(const std::string& path, const SourceLocation& includedAt, bool import) {
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(path, ec);
    std::string key = ec ? path : canonical.string();
    for (const auto& input : inputs_)
      if (input->key == key) {
        std::string chain;
        for (const auto& in : inputs_) chain += in->tokens.fileName() + " -> ";
        throw InputError(includedAt, fmt::format("include loop: {}{}", chain, path));
      }
    if (int(inputs_.size()) >= kMaxIncludeDepth)
      throw InputError(includedAt,
                       fmt::format("includes nested more than {} deep", kMaxIncludeDepth));
    pushStream(ByteStream::openFile(path), key, import, includedAt);
  }

  void pushStream(ByteStream stream, std::string key, bool import, const SourceLocation& at) {
    if (import) pushBlock(BlockKind::Import, at);
    auto input = std::make_unique<Input>(std::move(stream), std::move(key), options_);
    input->import = import;
    inputs_.push_back(std::move(input));
  }

  void run() {
    while (!inputs_.empty()) {
      Input& in = *inputs_.back();
      const PbrtToken& t = in.tokens.next();
      if (t.kind == PbrtToken::Kind::End) {
        in.progress.finish();
        bool import = in.import;
        SourceLocation end = in.tokens.where(t);
        inputs_.pop_back();
        if (import) popBlock(BlockKind::Import, end);
        continue;
      }
      if (t.kind != PbrtToken::Kind::Word || t.isNumber()) {
        std::string what = t.kind == PbrtToken::Kind::String         ? "\"" + t.text + "\""
                           : t.kind == PbrtToken::Kind::OpenBracket  ? "'['"
                           : t.kind == PbrtToken::Kind::CloseBracket ? "']'"
                                                                     : "'" + t.text + "'";
        throw InputError(in.tokens.where(t),
                         fmt::format("expected a directive, found {} (too many values for the "
                                     "directive before?)",
                                     what));
      }
      directive(in, t.text, in.tokens.where(t));
      if (ended_) {
        // Blocks left open at WorldEnd are pbrt's business: it renders there.
        inputs_.clear();
        blocks_.clear();
        break;
      }
      in.progress.update(in.tokens.offset());
    }
    if (!blocks_.empty()) {
      const Block& open = blocks_.back();
      throw InputError(open.where, fmt::format("{} is never closed (the input ends first)",
                                               blockName(open.kind)));
    }
  }

  Scene finish(const std::string& name) {
    scene_.name = name;
    flushCurves();
    setSpotFalloff();
    makeEnvironment();
    makeCamera();
    pivotObjectInstancesAtTheCamera();
    if (scene_.meshes.empty() && scene_.geometries.empty() && scene_.suns.empty())
      warnings_.once("empty", fmt::format("{}: the scene has no shapes", name));
    return std::move(scene_);
  }

 private:
  struct Input {
    Input(ByteStream stream, std::string k, const LoadOptions& options)
        : tokens(std::move(stream)),
          key(std::move(k)),
          progress(options, tokens.fileName(), tokens.size()) {}
    PbrtTokenizer tokens;
    std::string key;
    LoadProgress progress;
    bool import = false;
  };

  // --------------------------------------------------------------- arguments

  [[noreturn]] void fail(const SourceLocation& where, const std::string& message) {
    throw InputError(where, message);
  }

  float number(Input& in, const char* directive) {
    const PbrtToken& t = in.tokens.next();
    if (t.kind == PbrtToken::Kind::Word && t.isNumber()) {
      if (auto v = parsePbrtNumber(t.text)) return float(*v);
      fail(in.tokens.where(t), fmt::format("{}: '{}' is not a finite number", directive, t.text));
    }
    fail(in.tokens.where(t),
         fmt::format("{}: expected a number, found {}", directive, describe(t)));
  }

  std::string describe(const PbrtToken& t) {
    switch (t.kind) {
      case PbrtToken::Kind::End:
        return "the end of the file";
      case PbrtToken::Kind::String:
        return "\"" + t.text + "\"";
      case PbrtToken::Kind::OpenBracket:
        return "'['";
      case PbrtToken::Kind::CloseBracket:
        return "']'";
      default:
        return "'" + t.text + "'";
    }
  }

  std::string string(Input& in, const char* directive) {
    const PbrtToken& t = in.tokens.next();
    if (t.kind != PbrtToken::Kind::String)
      fail(in.tokens.where(t),
           fmt::format("{}: expected a quoted string, found {}", directive, describe(t)));
    return t.text;
  }

  // n numbers, with or without brackets.
  std::vector<float> numbers(Input& in, size_t n, const char* directive) {
    std::vector<float> v;
    bool bracket = in.tokens.peek().kind == PbrtToken::Kind::OpenBracket;
    if (bracket) in.tokens.next();
    for (size_t i = 0; i < n; ++i) v.push_back(number(in, directive));
    if (bracket) {
      const PbrtToken& t = in.tokens.next();
      if (t.kind != PbrtToken::Kind::CloseBracket)
        fail(in.tokens.where(t),
             fmt::format("{}: expected ']' after {} numbers, found {}", directive, n, describe(t)));
    }
    return v;
  }

  // A directive's parameter list, from `in` (the innermost input) and, where
  // `in` is an included file that ends inside the list, the files that
  // included it (pbrt-v3's smoke scene continues a medium's list so). Never
  // past an Import, which pbrt-v4 parses on its own. The exhausted files stay
  // on the stack until the run loop pops them.
  PbrtParams params(Input& in) {
    class IncludeChain final : public PbrtTokenSource {
     public:
      IncludeChain(std::vector<std::unique_ptr<Input>>& inputs, Input& in)
          : inputs_(inputs), last_(&in) {}
      const PbrtToken& next() override { return current().tokens.next(); }
      const PbrtToken& peek() override { return current().tokens.peek(); }
      SourceLocation where(const PbrtToken& token) const override {
        return last_->tokens.where(token);
      }

     private:
      Input& current() {
        size_t i = inputs_.size() - 1;
        while (i > 0 && !inputs_[i]->import &&
               inputs_[i]->tokens.peek().kind == PbrtToken::Kind::End)
          --i;
        last_ = inputs_[i].get();
        return *last_;
      }
      std::vector<std::unique_ptr<Input>>& inputs_;
      Input* last_;
    };
    if (&in != inputs_.back().get()) return PbrtParams::parse(in.tokens);
    IncludeChain chain(inputs_, in);
    return PbrtParams::parse(chain);
  }

  void reportUnused(const PbrtParams& p, const std::string& what) {
    for (const PbrtParam* q : p.unused())
      warnings_.once(what + "|" + q->declaration(),
                     fmt::format("{}: ignored parameter \"{}\" (not supported; first at {})", what,
                                 q->declaration(), q->where.toString()));
  }

  void skipped(const std::string& directive, const PbrtParams& p, const SourceLocation& where,
               const std::string& why) {
    p.markAllUsed();
    warnings_.once("directive|" + directive,
                   fmt::format("{} ignored: {} (first at {})", directive, why, where.toString()));
  }

  // ------------------------------------------------------------------ files

  std::string directoryOf(const std::string& file) {
    fs::path dir = fs::path(file).parent_path();
    return dir.empty() ? "." : dir.string();
  }

  // A file named in the scene: absolute, or relative to the main file's
  // directory (pbrt's rule), or else to the including file's.
  std::string resolve(const std::string& name, const SourceLocation& where, const char* what) {
    if (name.empty()) fail(where, fmt::format("empty {} name", what));
    std::string lookedFor;
    if (auto path = tryResolve(name, lookedFor)) return *path;
    fail(where, fmt::format("{} \"{}\" not found (looked for {})", what, name, lookedFor));
  }

  std::optional<std::string> tryResolve(const std::string& name, std::string& lookedFor) {
    fs::path p(name);
    std::vector<fs::path> tried;
    if (p.is_absolute()) {
      tried.push_back(p);
    } else {
      tried.push_back(fs::path(mainDirectory_) / p);
      if (!inputs_.empty()) {
        fs::path local = fs::path(directoryOf(inputs_.back()->tokens.fileName())) / p;
        if (local.lexically_normal() != tried[0].lexically_normal()) tried.push_back(local);
      }
    }
    std::error_code ec;
    for (const fs::path& candidate : tried)
      if (fs::is_regular_file(candidate, ec)) return candidate.lexically_normal().string();
    lookedFor.clear();
    for (const fs::path& candidate : tried)
      lookedFor += (lookedFor.empty() ? "" : ", ") + candidate.lexically_normal().string();
    return std::nullopt;
  }

  // ----------------------------------------------------------------- blocks

  void pushBlock(BlockKind kind, const SourceLocation& where) {
    if (blocks_.size() > 100000) fail(where, "blocks nested more than 100000 deep");
    blocks_.push_back({kind, state_, where});
  }

  void popBlock(BlockKind kind, const SourceLocation& where) {
    if (blocks_.empty())
      fail(where, fmt::format("{} without a matching {}",
                              kind == BlockKind::Transform ? "TransformEnd"
                              : kind == BlockKind::Object  ? "ObjectEnd"
                                                           : "AttributeEnd",
                              blockName(kind)));
    Block& b = blocks_.back();
    if (b.kind != kind) {
      // pbrt-v3 scenes close TransformBegin with AttributeEnd and the
      // reverse; accept those, but not an Import or object left open.
      bool interchangeable = (b.kind == BlockKind::Attribute || b.kind == BlockKind::Transform) &&
                             (kind == BlockKind::Attribute || kind == BlockKind::Transform);
      if (!interchangeable)
        fail(where, fmt::format("this closes the {} at {}", blockName(b.kind), b.where.toString()));
      warnings_.once("mismatched block",
                     fmt::format("{}: closes the {} at {} (accepted)", where.toString(),
                                 blockName(b.kind), b.where.toString()));
    }
    if (b.kind == BlockKind::Transform) {
      state_.ctm = b.saved.ctm;
      state_.ctmEnd = b.saved.ctmEnd;
    } else {
      state_ = std::move(b.saved);
    }
    blocks_.pop_back();
  }

  // ------------------------------------------------------------- transforms

  void applyTransform(const Affine3f& t) {
    if (activeStart_) state_.ctm = state_.ctm * t;
    if (activeEnd_) state_.ctmEnd = state_.ctmEnd * t;
  }

  void setTransform(const Affine3f& t) {
    if (activeStart_) state_.ctm = t;
    if (activeEnd_) state_.ctmEnd = t;
  }

  bool moving() const { return !sameTransform(state_.ctm, state_.ctmEnd); }

  // The motion of what is placed now at the top level (null: it does not
  // move). Motion inside an object definition makes a moving part instead
  // (addMesh, flushCurves).
  std::shared_ptr<const InstanceMotion> placedMotion(const SourceLocation& where) {
    if (!moving() || currentObject_) return nullptr;
    if (!lastMotion_ || !sameTransform(lastMotionFrom_, state_.ctm) ||
        !sameTransform(lastMotionTo_, state_.ctmEnd)) {
      checkEndInvertible(where);
      lastMotion_ = std::make_shared<const InstanceMotion>(state_.ctm, state_.ctmEnd);
      lastMotionFrom_ = state_.ctm;
      lastMotionTo_ = state_.ctmEnd;
    }
    return lastMotion_;
  }

  Affine3f matrixFrom(const std::vector<float>& m, const SourceLocation& where) {
    // pbrt lists the matrix column by column: m[12..14] is the translation.
    auto at = [&](int r, int c) { return m[size_t(c * 4 + r)]; };
    if (at(3, 0) != 0 || at(3, 1) != 0 || at(3, 2) != 0 || at(3, 3) == 0)
      fail(where, "projective transforms are not supported (the last row must be 0 0 0 w)");
    float w = at(3, 3);
    Affine3f a;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a.l[r][c] = at(r, c) / w;
      a.t[r] = at(r, 3) / w;
    }
    return a;
  }

  Affine3f lookAt(Vec3f eye, Vec3f look, Vec3f up, const SourceLocation& where) {
    Vec3f d = look - eye;
    if (!(length(d) > 0)) fail(where, "LookAt: the eye and the look-at point are the same");
    Vec3f dir = normalize(d);
    if (!(length(up) > 0)) fail(where, "LookAt: the up vector is zero");
    Vec3f right = cross(normalize(up), dir);
    if (!(length(right) > 1e-7f))
      fail(where, "LookAt: the up vector is parallel to the viewing direction");
    right = normalize(right);
    Vec3f newUp = cross(dir, right);
    Affine3f worldFromCamera;
    for (int r = 0; r < 3; ++r) {
      worldFromCamera.l[r][0] = right[r];
      worldFromCamera.l[r][1] = newUp[r];
      worldFromCamera.l[r][2] = dir[r];
    }
    worldFromCamera.t = eye;
    return worldFromCamera.inverse();
  }

  // -------------------------------------------------------------- directives

  // `name` is a copy: the token it came from changes as the arguments are read.
  void directive(Input& in, const std::string name, const SourceLocation& where) {
    if (!transformDirective(in, name, where) && !attributeDirective(in, name, where) &&
        !sceneContentDirective(in, name, where) && !optionDirective(in, name, where))
      fail(where, fmt::format("unknown directive '{}'", name));
  }

  // The current transform and named coordinate systems; false if `name` is
  // not one of these directives.
  bool transformDirective(Input& in, const std::string& name, const SourceLocation& where) {
    const char* n = name.c_str();
    if (name == "TransformBegin") {
      pushBlock(BlockKind::Transform, where);
    } else if (name == "TransformEnd") {
      popBlock(BlockKind::Transform, where);
    } else if (name == "Identity") {
      setTransform(Affine3f::identity());
    } else if (name == "Translate") {
      auto v = numbers(in, 3, n);
      applyTransform(Affine3f::translate({v[0], v[1], v[2]}));
    } else if (name == "Scale") {
      auto v = numbers(in, 3, n);
      applyTransform(Affine3f::scale({v[0], v[1], v[2]}));
    } else if (name == "Rotate") {
      auto v = numbers(in, 4, n);
      Vec3f axis(v[1], v[2], v[3]);
      if (!(length(axis) > 0)) fail(where, "Rotate: the axis is zero");
      applyTransform(Affine3f::rotate(axis, radians(v[0])));
    } else if (name == "LookAt") {
      auto v = numbers(in, 9, n);
      applyTransform(lookAt({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, {v[6], v[7], v[8]}, where));
    } else if (name == "ConcatTransform") {
      applyTransform(matrixFrom(numbers(in, 16, n), where));
    } else if (name == "Transform") {
      setTransform(matrixFrom(numbers(in, 16, n), where));
    } else if (name == "CoordinateSystem") {
      coordinateSystems_[string(in, n)] = {state_.ctm, state_.ctmEnd};
    } else if (name == "CoordSysTransform") {
      coordSysTransform(in, where);
    } else if (name == "ActiveTransform") {
      activeTransform(in);
    } else if (name == "TransformTimes") {
      auto v = numbers(in, 2, n);
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || v[0] > v[1])
        fail(where, fmt::format("TransformTimes: start {} must not be after end {}", v[0], v[1]));
      scene_.motionStart = v[0];
      scene_.motionEnd = v[1];
    } else {
      return false;
    }
    return true;
  }

  void coordSysTransform(Input& in, const SourceLocation& where) {
    std::string system = string(in, "CoordSysTransform");
    auto it = coordinateSystems_.find(system);
    if (it == coordinateSystems_.end()) {
      std::string known;
      for (const auto& [k, v] : coordinateSystems_) known += (known.empty() ? "" : ", ") + k;
      fail(where, fmt::format("CoordSysTransform: no coordinate system \"{}\" (defined: {})",
                              system, known.empty() ? "none" : known));
    }
    if (activeStart_) state_.ctm = it->second.first;
    if (activeEnd_) state_.ctmEnd = it->second.second;
  }

  void activeTransform(Input& in) {
    const PbrtToken& t = in.tokens.next();
    if (t.kind != PbrtToken::Kind::Word ||
        (t.text != "StartTime" && t.text != "EndTime" && t.text != "All"))
      fail(in.tokens.where(t),
           fmt::format("ActiveTransform: expected StartTime, EndTime or All, found {}",
                       describe(t)));
    activeStart_ = t.text != "EndTime";
    activeEnd_ = t.text != "StartTime";
  }

  // Attribute blocks and defaults, and object definitions and instances;
  // false if `name` is not one of these directives.
  bool attributeDirective(Input& in, const std::string& name, const SourceLocation& where) {
    const char* n = name.c_str();
    if (name == "AttributeBegin") {
      pushBlock(BlockKind::Attribute, where);
    } else if (name == "AttributeEnd") {
      popBlock(BlockKind::Attribute, where);
    } else if (name == "Attribute") {
      noteDialect(Dialect::V4);
      attribute(in, where);
    } else if (name == "ReverseOrientation") {
      // Shading and emission are two-sided in Ferry: orientation changes nothing.
      state_.reverseOrientation = !state_.reverseOrientation;
    } else if (name == "ObjectBegin") {
      objectBegin(string(in, n), where);
    } else if (name == "ObjectEnd") {
      objectEnd(where);
    } else if (name == "ObjectInstance") {
      objectInstance(string(in, n), where);
    } else {
      return false;
    }
    return true;
  }

  void attribute(Input& in, const SourceLocation& where) {
    std::string target = string(in, "Attribute");
    if (target != "shape" && target != "light" && target != "material" && target != "medium" &&
        target != "texture")
      fail(where, fmt::format("Attribute: unknown target \"{}\" (shape, light, material, medium, "
                              "texture)",
                              target));
    PbrtParams p = params(in);
    PbrtParams& defaults = state_.attributes[target];
    for (const PbrtParam& param : p.all()) {
      PbrtParams merged;
      merged.add(param);
      for (const PbrtParam& old : defaults.all())
        if (old.name != param.name) merged.add(old);
      defaults = std::move(merged);
    }
  }

  // Shapes, lights, materials, textures and media; false if `name` is not one
  // of these directives.
  bool sceneContentDirective(Input& in, const std::string& name, const SourceLocation& where) {
    const char* n = name.c_str();
    if (name == "Shape") {
      std::string type = string(in, n);
      shape(type, withDefaults(params(in), "shape"), where);
    } else if (name == "LightSource") {
      std::string type = string(in, n);
      light(type, withDefaults(params(in), "light"), where);
    } else if (name == "AreaLightSource") {
      std::string type = string(in, n);
      areaLight(type, withDefaults(params(in), "light"), where);
    } else if (name == "Material") {
      std::string type = string(in, n);
      PbrtParams p = withDefaults(params(in), "material");
      noteMaterialDialect(type);
      state_.material = materials_.addMaterial({type, std::move(p), where, ""});
    } else if (name == "MakeNamedMaterial") {
      makeNamedMaterial(in, where);
    } else if (name == "NamedMaterial") {
      std::string materialName = string(in, n);
      auto id = materials_.namedMaterial(materialName);
      if (!id) fail(where, fmt::format("NamedMaterial: no material named \"{}\"", materialName));
      state_.material = *id;
    } else if (name == "Texture") {
      texture(in, where);
    } else if (name == "MakeNamedMedium") {
      makeNamedMedium(in, where);
    } else if (name == "MediumInterface") {
      state_.mediumInside = string(in, n);
      state_.mediumOutside =
          in.tokens.peek().kind == PbrtToken::Kind::String ? string(in, n) : state_.mediumInside;
      mediumOf(state_.mediumInside, where);
      mediumOf(state_.mediumOutside, where);
    } else if (name == "CameraMedium") {
      state_.mediumOutside = string(in, n);
      mediumOf(state_.mediumOutside, where);
    } else {
      return false;
    }
    return true;
  }

  // ------------------------------------------------------------------ media

  // The medium named `name` ("": vacuum); an error names an undefined one.
  int32_t mediumOf(const std::string& name, const SourceLocation& where) {
    if (name.empty()) return kNoMedium;
    auto it = namedMedia_.find(name);
    if (it == namedMedia_.end())
      fail(where, fmt::format("no medium named \"{}\" (MakeNamedMedium defines one first)", name));
    return it->second;
  }

  // The media on the sides of the shapes being defined now.
  MediumInterface currentMedia(const SourceLocation& where) {
    return {mediumOf(state_.mediumInside, where), mediumOf(state_.mediumOutside, where)};
  }

  // `values` (nx x ny x nz, checked) as a grid; errors at the parameter.
  std::shared_ptr<const DensityGrid> voxelGrid(const PbrtParam& values, int nx, int ny, int nz,
                                               const std::string& what, const SourceLocation& where,
                                               int stride = 1, int offset = 0) {
    if (nx <= 0 || ny <= 0 || nz <= 0)
      fail(where, fmt::format("{}: nx, ny, nz ({} {} {}) must be positive", what, nx, ny, nz));
    const uint64_t count = uint64_t(nx) * uint64_t(ny) * uint64_t(nz);
    if (count * uint64_t(stride) != values.floats.size())
      PbrtParams::fail(
          values, fmt::format("{} values for {}nx * ny * nz = {} x {} x {} = {}",
                              values.floats.size(), stride > 1 ? fmt::format("{} x ", stride) : "",
                              nx, ny, nz, count * uint64_t(stride)));
    std::vector<float> v(count);
    for (uint64_t i = 0; i < count; ++i)
      v[i] = values.floats[i * uint64_t(stride) + uint64_t(offset)];
    try {
      return std::make_shared<DensityGrid>(nx, ny, nz, std::move(v));
    } catch (const std::invalid_argument& e) {
      PbrtParams::fail(values, e.what());
    }
  }

  // pbrt-v4's rgbgrid: one RGB per voxel of "sigma_a", "sigma_s" and "Le".
  std::shared_ptr<const RgbGrids> rgbGrids(const PbrtParams& p, const std::string& what,
                                           const SourceLocation& where) {
    const int nx = p.getInt("nx", 1), ny = p.getInt("ny", 1), nz = p.getInt("nz", 1);
    const PbrtParam* sa = p.getArray("sigma_a", {"rgb"});
    const PbrtParam* ss = p.getArray("sigma_s", {"rgb"});
    const PbrtParam* le = p.getArray("Le", {"rgb"});
    if (!sa && !ss)
      fail(where,
           fmt::format("{} needs \"rgb sigma_a\" or \"rgb sigma_s\" (an RGB per voxel)", what));
    if (le && !sa) fail(where, fmt::format("{}: \"Le\" needs \"sigma_a\" too", what));
    auto grids = std::make_shared<RgbGrids>();
    auto channels = [&](const PbrtParam* param, RgbGrids::Channels& out) {
      if (param)
        for (int c = 0; c < 3; ++c)
          out[size_t(c)] = voxelGrid(*param, nx, ny, nz, what, where, 3, c);
    };
    channels(sa, grids->sigmaA);
    channels(ss, grids->sigmaS);
    channels(le, grids->emission);
    return grids;
  }

  // Emission by temperature: the grid in kelvin and pbrt-v4's offset and scale.
  TemperatureEmission temperatureEmission(const PbrtParams& p,
                                          std::shared_ptr<const DensityGrid> kelvin) {
    static const std::vector<Vec3f> table = [] {
      std::vector<Vec3f> t(kBlackbodyEntries);
      for (size_t i = 0; i < t.size(); ++i) {
        const float k = float(i) * kBlackbodyStep;
        if (k > 100) t[i] = spectrumToRgb(blackbodySpectrum(k), SpectrumUse::Illuminant);
      }
      return t;
    }();
    TemperatureEmission t;
    t.kelvin = std::move(kelvin);
    t.offset = p.getFloat("temperatureoffset", p.getFloat("temperaturecutoff", 0));
    t.scale = p.getFloat("temperaturescale", 1);
    t.table = table;
    t.step = kBlackbodyStep;
    return t;
  }

  // A grid medium's emission as pbrt-v4's uniformgrid has it: "Le" or a
  // "temperature" grid, times the "Lescale" grid (one value per voxel;
  // absent, a single voxel of 1, which fades towards the box's faces as
  // pbrt's lookup of it does).
  void gridEmission(const PbrtParams& p, Medium& m, int nx, int ny, int nz, const std::string& what,
                    const SourceLocation& where) {
    const PbrtParam* temperature = p.getArray("temperature", {"float"});
    if (temperature && p.has("Le"))
      fail(where, fmt::format("{}: both \"Le\" and \"temperature\" are given", what));
    const Vec3f le = materials_.constantColor(p, "Le", Vec3f(0), SpectrumUse::Illuminant);
    const PbrtParam* leScale = p.getArray("Lescale", {"float"});
    if (!temperature && !(maxComponent(le) > 0)) {
      p.find("temperatureoffset");
      p.find("temperaturecutoff");
      p.find("temperaturescale");
      return;
    }
    m.emissionScale = leScale ? voxelGrid(*leScale, nx, ny, nz, what, where)
                              : std::make_shared<DensityGrid>(1, 1, 1, std::vector<float>{1});
    if (temperature) {
      m.temperature = std::make_shared<TemperatureEmission>(
          temperatureEmission(p, voxelGrid(*temperature, nx, ny, nz, what, where)));
      m.emission = Vec3f(1);
    } else {
      m.emission = le;
    }
  }

  // pbrt-v3's homogeneous and heterogeneous media and pbrt-v4's homogeneous,
  // uniformgrid, rgbgrid, cloud and nanovdb (given a .vdb file), with the CTM here placing a grid's
  // p0-p1 box.
  void makeNamedMedium(Input& in, const SourceLocation& where) {
    const std::string name = string(in, "MakeNamedMedium");
    PbrtParams p = withDefaults(params(in), "medium");
    if (!p.has("type"))
      fail(where, fmt::format("MakeNamedMedium \"{}\" has no \"string type\"", name));
    const std::string type = p.getString("type", "");
    const std::string what = fmt::format("MakeNamedMedium \"{}\" (\"{}\")", name, type);
    if (type == "nanovdb") {
      const std::string file = p.getString("filename", "");
      if (file.empty()) fail(where, fmt::format("{} needs \"string filename\"", what));
      if (!file.ends_with(".vdb") && !file.ends_with(".nvdb"))
        fail(where, fmt::format("{}: \"{}\": a NanoVDB (.nvdb) or OpenVDB (.vdb) file expected",
                                what, file));
    }
    if (type != "homogeneous" && type != "heterogeneous" && type != "uniformgrid" &&
        type != "nanovdb" && type != "rgbgrid" && type != "cloud") {
      p.markAllUsed();
      warnings_.once("medium|" + type,
                     fmt::format("{} is not supported: the medium is left out (vacuum; first at "
                                 "{})",
                                 what, where.toString()));
      namedMedia_[name] = kNoMedium;
      return;
    }
    const float g = p.getFloat("g", 0);
    if (!(std::abs(g) < 1)) fail(where, fmt::format("{}: \"g\" {} must be in (-1, 1)", what, g));
    const Vec3f p0 = p.getPoint3("p0").value_or(Vec3f(0)),
                p1 = p.getPoint3("p1").value_or(Vec3f(1));
    const bool boxed =
        type == "heterogeneous" || type == "uniformgrid" || type == "rgbgrid" || type == "cloud";
    if (boxed && !(p0.x < p1.x && p0.y < p1.y && p0.z < p1.z))
      fail(where, fmt::format("{}: p0 must be below p1 on every axis", what));
    Medium m;
    if (type == "rgbgrid") {
      m = rgbGridMedium(name, rgbGrids(p, what, where), p.getFloat("scale", 1),
                        p.getFloat("Lescale", 1), g, state_.ctm, Box3f{p0, p1});
    } else {
      // pbrt-v3's defaults (its MakeMedium); pbrt-v4's grids and clouds default to 1.
      const bool v4 = type != "homogeneous" && type != "heterogeneous";
      Vec3f sigmaA = v4 ? Vec3f(1) : Vec3f(0.0011f, 0.0024f, 0.014f);
      Vec3f sigmaS = v4 ? Vec3f(1) : Vec3f(2.55f, 3.21f, 3.77f);
      if (const std::string preset = p.getString("preset", ""); !preset.empty()) {
        if (!mediumPreset(preset, sigmaA, sigmaS))
          warnings_.once("preset|" + preset,
                         fmt::format("{}: unknown preset \"{}\" (its default coefficients are "
                                     "used; at {})",
                                     what, preset, where.toString()));
      }
      const float scale = p.getFloat("scale", 1);
      sigmaA = materials_.constantColor(p, "sigma_a", sigmaA, SpectrumUse::Reflectance) * scale;
      sigmaS = materials_.constantColor(p, "sigma_s", sigmaS, SpectrumUse::Reflectance) * scale;
      if (!isFinite(sigmaA) || !isFinite(sigmaS) || std::min({sigmaA.x, sigmaA.y, sigmaA.z}) < 0 ||
          std::min({sigmaS.x, sigmaS.y, sigmaS.z}) < 0)
        fail(where, fmt::format("{}: sigma_a and sigma_s must be finite and not negative", what));
      if (type == "homogeneous") {
        m.name = name;
        m.sigmaA = sigmaA;
        m.sigmaS = sigmaS;
        m.g = g;
        m.emission = materials_.constantColor(p, "Le", Vec3f(0), SpectrumUse::Illuminant) *
                     p.getFloat("Lescale", 1);
      } else if (type == "cloud") {
        CloudDensity cloud;
        cloud.density = p.getFloat("density", 1);
        cloud.wispiness = p.getFloat("wispiness", 1);
        cloud.frequency = p.getFloat("frequency", 5);
        cloud.box = Box3f{p0, p1};
        if (!(cloud.density >= 0) || !std::isfinite(cloud.density) ||
            !std::isfinite(cloud.wispiness) || !std::isfinite(cloud.frequency))
          fail(where, fmt::format("{}: \"density\", \"wispiness\" and \"frequency\" must be "
                                  "finite, the density not negative",
                                  what));
        m = cloudMedium(name, sigmaA, sigmaS, g, cloud, state_.ctm);
      } else if (type == "nanovdb") {
        // Its grids, from a .nvdb file or the same as an OpenVDB file:
        // "density", and "temperature" if there.
        const std::string path = resolve(p.getString("filename", ""), where, "volume file");
        VdbDensity vdb, kelvin;
        try {
          std::tie(vdb, kelvin) = path.ends_with(".nvdb") ? readNanoVdbDensityAndTemperature(path)
                                                          : readVdbDensityAndTemperature(path);
        } catch (const InputError& e) {
          fail(where, fmt::format("{}: {}", what, e.what()));
        }
        m = gridMedium(name, sigmaA, sigmaS, g, vdb.grid, state_.ctm, vdb.box);
        const float leScale = p.getFloat("Lescale", 1);
        if (kelvin.grid && leScale > 0) {
          TemperatureEmission t = temperatureEmission(p, kelvin.grid);
          // Its own box: its unit cube from the density's.
          const Vec3f size = kelvin.box.size();
          t.unitScale = vdb.box.size() / size;
          t.unitOffset = (vdb.box.lower - kelvin.box.lower) / size;
          m.temperature = std::make_shared<TemperatureEmission>(std::move(t));
          m.emission = Vec3f(leScale);
        } else {
          p.find("temperaturecutoff");
          p.find("temperatureoffset");
          p.find("temperaturescale");
        }
      } else {
        const int nx = p.getInt("nx", 1), ny = p.getInt("ny", 1), nz = p.getInt("nz", 1);
        const PbrtParam* density = p.getArray("density", {"float"});
        if (!density) fail(where, fmt::format("{} needs \"float density\"", what));
        m = gridMedium(name, sigmaA, sigmaS, g, voxelGrid(*density, nx, ny, nz, what, where),
                       state_.ctm, Box3f{p0, p1});
        gridEmission(p, m, nx, ny, nz, what, where);
      }
    }
    reportUnused(p, what);
    scene_.media.push_back(std::move(m));
    namedMedia_[name] = int32_t(scene_.media.size() - 1);
  }

  void makeNamedMaterial(Input& in, const SourceLocation& where) {
    std::string materialName = string(in, "MakeNamedMaterial");
    PbrtParams p = withDefaults(params(in), "material");
    std::string type = p.getString("type", "");
    if (!p.has("type"))
      fail(where, fmt::format("MakeNamedMaterial \"{}\" has no \"string type\"", materialName));
    noteMaterialDialect(type);
    materials_.nameMaterial(materialName,
                            materials_.addMaterial({type, std::move(p), where, materialName}));
  }

  // The world block, included files, and the camera, film and rendering
  // options; false if `name` is not one of these directives.
  bool optionDirective(Input& in, const std::string& name, const SourceLocation& where) {
    const char* n = name.c_str();
    if (name == "WorldBegin") {
      state_.ctm = state_.ctmEnd = Affine3f::identity();
      coordinateSystems_["world"] = {state_.ctm, state_.ctmEnd};
      inWorld_ = true;
    } else if (name == "WorldEnd") {
      worldEnd(in, where);
    } else if (name == "Include" || name == "Import") {
      std::string file = string(in, n);
      pushFile(resolve(file, where, name.c_str()), where, name == "Import");
    } else if (name == "Camera") {
      std::string type = string(in, n);
      camera(type, params(in), where);
    } else if (name == "Film") {
      std::string type = string(in, n);
      film(type, params(in), where);
    } else if (name == "Integrator") {
      std::string type = string(in, n);
      scene_.integrator = type;
      if (type == "whitted" || type == "directlighting") noteDialect(Dialect::V3);
      if (type == "lightpath" || type == "randomwalk" || type == "simplepath" ||
          type == "simplevolpath" || type == "aov")
        noteDialect(Dialect::V4);
      PbrtParams p = params(in);
      if (p.find("maxdepth")) {
        const int depth = p.getInt("maxdepth", 5);
        if (depth < 0)
          fail(where, fmt::format("Integrator: \"integer maxdepth\" {} must be 0 or more", depth));
        scene_.integratorMaxDepth = depth;
      }
      skipped(name, p, where,
              (integratorWantsLightPaths(type)
                   ? fmt::format("\"{}\": Ferry renders it as camera paths and light paths "
                                 "combined by MIS (the light-paths setting)",
                                 type)
                   : fmt::format("\"{}\": Ferry's wavefront path tracer chooses its own", type)) +
                  (scene_.integratorMaxDepth ? "; its \"maxdepth\" is the default max-depth" : ""));
    } else if (name == "Sampler") {
      std::string type = string(in, n);
      skipped(name, params(in), where,
              fmt::format("\"{}\": Ferry's sampler and samples per pixel are render settings "
                          "(Sobol' by default)",
                          type));
    } else if (name == "SurfaceIntegrator" || name == "VolumeIntegrator" || name == "PixelFilter" ||
               name == "Accelerator" || name == "Renderer") {
      std::string type = string(in, n);
      skipped(name, params(in), where,
              fmt::format("\"{}\": Ferry's wavefront path tracer chooses its own", type));
    } else if (name == "Option") {
      noteDialect(Dialect::V4);
      skipped(name, params(in), where, "rendering options are Ferry's own");
    } else if (name == "ColorSpace") {
      noteDialect(Dialect::V4);
      std::string space = string(in, n);
      if (space != "srgb")
        warnings_.once("colorspace", fmt::format("ColorSpace \"{}\" ignored: Ferry renders in "
                                                 "linear sRGB (first at {})",
                                                 space, where.toString()));
    } else {
      return false;
    }
    return true;
  }

  PbrtParams withDefaults(PbrtParams p, const std::string& target) {
    auto it = state_.attributes.find(target);
    if (it != state_.attributes.end()) p.addDefaults(it->second);
    return p;
  }

  void worldEnd(Input& in, const SourceLocation& where) {
    const PbrtToken& t = in.tokens.peek();
    if (t.kind != PbrtToken::Kind::End || inputs_.size() > 1)
      warnings_.once(
          "after WorldEnd",
          fmt::format("{}: WorldEnd ends the scene; what follows it is ignored", where.toString()));
    ended_ = true;
  }

  void camera(const std::string& type, const PbrtParams& p, const SourceLocation& where) {
    CameraDefinition c;
    c.cameraFromWorld = state_.ctm;
    c.where = where;
    if (moving()) {  // pbrt's camera-to-world, animated
      const float det = state_.ctmEnd.determinant();
      if (!std::isfinite(det) || det == 0 || state_.ctm.determinant() == 0)
        fail(where, "Camera: the camera transform is singular");
      c.motion =
          std::make_shared<const InstanceMotion>(state_.ctm.inverse(), state_.ctmEnd.inverse());
    }
    c.shutterOpen = p.getFloat("shutteropen", 0);
    c.shutterClose = p.getFloat("shutterclose", 1);
    if (!std::isfinite(c.shutterOpen) || !std::isfinite(c.shutterClose) ||
        c.shutterClose < c.shutterOpen)
      fail(where, fmt::format("Camera: \"float shutterclose\" {} must not be before "
                              "\"float shutteropen\" {}",
                              c.shutterClose, c.shutterOpen));
    if (type == "perspective") {
      c.fov = p.getFloat("fov", 90);
      if (!(c.fov > 0 && c.fov < 180))
        fail(where, fmt::format("Camera: fov {} must be between 0 and 180", c.fov));
      // pbrt-v3's and v4's thin lens, in camera space (default: a pinhole).
      c.lensRadius = p.getFloat("lensradius", 0);
      c.focalDistance = p.getFloat("focaldistance", 1e6f);
      if (!(c.lensRadius >= 0) || !std::isfinite(c.lensRadius))
        fail(where, fmt::format("Camera: \"float lensradius\" {} must be 0 or more", c.lensRadius));
      if (!(c.focalDistance > 0) || !std::isfinite(c.focalDistance))
        fail(where,
             fmt::format("Camera: \"float focaldistance\" {} must be positive", c.focalDistance));
    } else {
      p.markAllUsed();
      warnings_.once("camera type", fmt::format("Camera \"{}\" is not supported: using a "
                                                "perspective camera with fov 90 at the same place "
                                                "(at {})",
                                                type, where.toString()));
    }
    reportUnused(p, fmt::format("Camera \"{}\"", type));
    scene_.cameraMedium = mediumOf(state_.mediumOutside, where);
    camera_ = c;
    auto inverse = [](const Affine3f& m) { return m.determinant() != 0 ? m.inverse() : m; };
    coordinateSystems_["camera"] = {inverse(state_.ctm), inverse(state_.ctmEnd)};
  }

  void film(const std::string& type, const PbrtParams& p, const SourceLocation& where) {
    if (type == "image") noteDialect(Dialect::V3);
    if (type == "rgb" || type == "gbuffer" || type == "spectral") noteDialect(Dialect::V4);
    if (type != "image" && type != "rgb" && type != "gbuffer" && type != "spectral")
      fail(where,
           fmt::format("Film \"{}\" is not a pbrt film (image, rgb, gbuffer, spectral)", type));
    if (type == "gbuffer" || type == "spectral")
      warnings_.once(
          "film|" + type,
          fmt::format("Film \"{}\": written as an RGB image, without its {} (at {})", type,
                      type == "gbuffer" ? "geometry channels" : "spectral channels",
                      where.toString()));
    int w = p.getInt("xresolution", 1280), h = p.getInt("yresolution", 720);
    if (w < 1 || h < 1 || w > kMaxFilmSide || h > kMaxFilmSide)
      fail(where, fmt::format("Film: resolution {} x {} must be between 1 and {} per side", w, h,
                              kMaxFilmSide));
    scene_.filmWidth = w;
    scene_.filmHeight = h;
    filmWidth_ = w;
    filmHeight_ = h;
    std::string file = p.getString("filename", "");
    if (!file.empty()) scene_.filmFilename = file;
    // pbrt-v3 multiplies the radiance by "scale"; pbrt-v4's sensor by its
    // imaging ratio, exposure time x ISO / 100 (the exposure time, from the
    // camera's shutter, is applied with the camera: makeCamera).
    float filmScale = 1;
    if (p.find("scale")) {
      const float scale = p.getFloat("scale", 1);
      if (!(scale > 0) || !std::isfinite(scale))
        fail(where, fmt::format("Film: \"float scale\" {} must be positive", scale));
      filmScale *= scale;
    }
    if (p.find("iso")) {
      const float iso = p.getFloat("iso", 100);
      if (!(iso > 0) || !std::isfinite(iso))
        fail(where, fmt::format("Film: \"float iso\" {} must be positive", iso));
      filmScale *= iso / 100;
    }
    scene_.filmScale = filmScale;
    // The clamp of each camera sample: v3 on its luminance, v4 on its
    // largest channel (default: none, pbrt's infinity).
    auto clampLimit = [&](const char* name) {
      if (!p.find(name)) return 0.0f;
      const float limit = p.getFloat(name, 0);
      if (!(limit > 0))
        fail(where, fmt::format("Film: \"float {}\" {} must be positive", name, limit));
      return std::isfinite(limit) ? limit : 0.0f;
    };
    scene_.filmMaxSampleLuminance = clampLimit("maxsampleluminance");
    scene_.filmMaxComponentValue = clampLimit("maxcomponentvalue");
    if (const PbrtParam* crop = p.find("cropwindow")) {
      const std::vector<float>& c = crop->floats;
      if (crop->type != "float" || c.size() != 4 || !isCropWindow(c[0], c[1], c[2], c[3]))
        fail(where,
             "Film: \"float cropwindow\" expects four fractions x0 x1 y0 y1 with "
             "0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1");
      scene_.filmCrop = std::array<float, 4>{c[0], c[1], c[2], c[3]};
    }
    reportUnused(p, fmt::format("Film \"{}\"", type));
  }

  void texture(Input& in, const SourceLocation& where) {
    PbrtTextureDefinition t;
    t.name = string(in, "Texture");
    std::string type = string(in, "Texture");
    if (type == "float")
      t.isFloat = true;
    else if (type == "spectrum" || type == "color" || type == "rgb")
      t.isFloat = false;
    else
      fail(where,
           fmt::format("Texture \"{}\": type \"{}\" is neither float nor spectrum", t.name, type));
    t.className = string(in, "Texture");
    t.params = withDefaults(params(in), "texture");
    t.where = where;
    t.transform = state_.ctm;
    t.transformIsWorldToTexture = dialect_ == Dialect::V3;
    materials_.defineTexture(std::move(t));
  }

  void objectBegin(const std::string& name, const SourceLocation& where) {
    if (currentObject_)
      fail(where, fmt::format("ObjectBegin \"{}\" inside the definition of \"{}\"", name,
                              scene_.objects[size_t(*currentObject_)].name));
    pushBlock(BlockKind::Object, where);
    if (objects_.count(name))
      warnings_.once("object redefined|" + name,
                     fmt::format("{}: object \"{}\" redefined; later instances use the new one",
                                 where.toString(), name));
    Object o;
    o.name = name;
    scene_.objects.push_back(std::move(o));
    currentObject_ = int32_t(scene_.objects.size() - 1);
    objects_[name] = *currentObject_;
    flushCurves();
  }

  void objectEnd(const SourceLocation& where) {
    if (!currentObject_) fail(where, "ObjectEnd without ObjectBegin");
    popBlock(BlockKind::Object, where);
    flushCurves();
    if (scene_.objects[size_t(*currentObject_)].slots() == 0 &&
        !movingParts_.count(*currentObject_))
      warnings_.once("empty object|" + scene_.objects[size_t(*currentObject_)].name,
                     fmt::format("{}: object \"{}\" has no shapes", where.toString(),
                                 scene_.objects[size_t(*currentObject_)].name));
    currentObject_.reset();
  }

  void objectInstance(const std::string& name, const SourceLocation& where) {
    if (currentObject_)
      fail(where, fmt::format("ObjectInstance \"{}\" inside an object definition", name));
    auto it = objects_.find(name);
    if (it == objects_.end())
      fail(where, fmt::format("ObjectInstance: no object named \"{}\"", name));
    checkInvertible(where);
    if (scene_.objects[size_t(it->second)].slots() > 0) {
      scene_.instances.push_back({it->second, state_.ctm, placedMotion(where)});
      if (scene_.instances.back().motion)
        movingObjectInstances_.push_back({scene_.instances.size() - 1, state_.ctm, state_.ctmEnd});
    }
    // Its moving parts, each moved by the part's motion, then the instance's.
    if (auto parts = movingParts_.find(it->second); parts != movingParts_.end()) {
      if (moving()) checkEndInvertible(where);
      for (const MovingPart& part : parts->second) {
        scene_.instances.push_back({part.object, state_.ctm * part.start,
                                    std::make_shared<const InstanceMotion>(InstanceMotion::nested(
                                        state_.ctm, state_.ctmEnd, part.start, part.end))});
        // (pbrt-v4 turns the instance about the camera: made again at the end.)
        movingPartInstances_.push_back(
            {scene_.instances.size() - 1, state_.ctm, state_.ctmEnd, part.start, part.end});
      }
    }
  }

  // pbrt-v4 interpolates a moving ObjectInstance's transform in its render
  // space, whose origin is the camera: the rotation turns about the camera
  // (pbrt-v3's, about the world's origin). Known once the file is read.
  void pivotObjectInstancesAtTheCamera() {
    if (dialect_ != Dialect::V4 || (movingObjectInstances_.empty() && movingPartInstances_.empty()))
      return;
    const CameraDefinition c = camera_.value_or(CameraDefinition{});
    const float det = c.cameraFromWorld.determinant();
    if (!std::isfinite(det) || det == 0) return;  // makeCamera says so
    // pbrt-v4's render space: centred where the camera is halfway through its motion.
    const Vec3f camera = c.motion ? c.motion->at(0.5f).transformPoint(Vec3f(0))
                                  : c.cameraFromWorld.inverse().transformPoint(Vec3f(0));
    for (const MovingObjectInstance& m : movingObjectInstances_)
      scene_.instances[m.instance].motion =
          std::make_shared<const InstanceMotion>(m.start, m.end, camera);
    for (const MovingPartInstance& m : movingPartInstances_)
      scene_.instances[m.instance].motion = std::make_shared<const InstanceMotion>(
          InstanceMotion::nested(m.start, m.end, m.partStart, m.partEnd, camera));
  }

  void checkEndInvertible(const SourceLocation& where) {
    const float det = state_.ctmEnd.determinant();
    if (!std::isfinite(det) || det == 0)
      fail(where, "the end transform is singular (a zero scale?) or not finite");
  }

  void checkInvertible(const SourceLocation& where) {
    float det = state_.ctm.determinant();
    if (!std::isfinite(det) || det == 0)
      fail(where, "the current transform is singular (a zero scale?) or not finite");
  }

  // ----------------------------------------------------------------- lights

  Vec3f lightScale(const PbrtParams& p) {
    const PbrtParam* s = p.find("scale");
    if (!s) return Vec3f(1);
    if (s->type == "float") return Vec3f(p.getFloat("scale", 1));
    return materials_.constantColor(p, "scale", Vec3f(1), SpectrumUse::Reflectance);
  }

  void light(const std::string& type, const PbrtParams& p, const SourceLocation& where) {
    const std::string what = fmt::format("LightSource \"{}\"", type);
    if (type == "infinite") {
      if (currentObject_) fail(where, "infinite lights cannot be part of an object");
      infiniteLights_.push_back(
          {p, state_.ctm.determinant() != 0 ? state_.ctm.inverse() : state_.ctm, where});
      return;  // parameters are read (and reported) when the environment is made
    }
    if (type == "distant") {
      Vec3f L = materials_.constantColor(p, "L", Vec3f(1), SpectrumUse::Illuminant) * lightScale(p);
      Vec3f from = p.getPoint3("from").value_or(Vec3f(0, 0, 0));
      Vec3f to = p.getPoint3("to").value_or(Vec3f(0, 0, 1));
      if (p.has("illuminance")) {
        float e = p.getFloat("illuminance", 1);
        float y = luminance(L);
        if (y > 0) L = L * (e / y);
      }
      Vec3f dir = state_.ctm.transformVector(from - to);
      if (!(length(dir) > 0)) fail(where, "distant light: from and to are the same point");
      SunLight sun;
      sun.direction = normalize(dir);
      sun.irradiance = L;
      scene_.suns.push_back(sun);
    } else if (type == "point" || type == "spot" || type == "goniometric" || type == "projection") {
      if (type == "goniometric" || type == "projection") {
        p.find("mapname");
        p.find("filename");
        p.find("fov");
        warnings_.once("light|" + type, fmt::format("{} is approximated by a point light (its "
                                                    "image is ignored; first at {})",
                                                    what, where.toString()));
      }
      PointLight light;
      light.intensity =
          materials_.constantColor(p, "I", Vec3f(1), SpectrumUse::Illuminant) * lightScale(p);
      // pbrt-v4's "float power" (watts; absent or <= 0: not used): the
      // intensity is scaled by power / k_e, k_e the solid angle a unit
      // intensity fills (pbrt-v4's PointLight and SpotLight::Create).
      const float power = p.getFloat("power", -1);
      Vec3f from = p.getPoint3("from").value_or(Vec3f(0, 0, 0));
      light.position = state_.ctm.transformPoint(from);
      if (type == "spot") {
        Vec3f to = p.getPoint3("to").value_or(Vec3f(0, 0, 1));
        Vec3f d = state_.ctm.transformVector(to - from);
        if (!(length(d) > 0)) fail(where, "spot light: from and to are the same point");
        light.direction = normalize(d);
        const float cone = std::clamp(p.getFloat("coneangle", 30), 0.0f, 180.0f);
        const float delta = std::clamp(p.getFloat("conedeltaangle", 5), 0.0f, cone);
        light.cosTotalWidth = std::cos(cone * kPi / 180);
        light.cosFalloffStart = std::cos((cone - delta) * kPi / 180);
        // Quartic or smoothstep: which pbrt wrote the file (finish()).
        light.falloff = PointLight::Falloff::SmoothStep;
        if (power > 0)
          light.intensity *=
              power /
              (2 * kPi *
               ((1 - light.cosFalloffStart) + (light.cosFalloffStart - light.cosTotalWidth) / 2));
      } else if (power > 0 && type == "point") {
        // v3 point lights place themselves with the CTM too (from is in light space).
        light.intensity *= power / (4 * kPi);
      }
      if (power > 0 && (type == "goniometric" || type == "projection"))
        warnings_.once("light power|" + type,
                       fmt::format("{}: \"float power\" ignored (its image is; first at {})", what,
                                   where.toString()));
      if (!isFinite(light.position)) fail(where, "light position is not finite");
      if (maxComponent(light.intensity) > 0) scene_.pointLights.push_back(light);
    } else {
      p.markAllUsed();
      warnings_.once(
          "light|" + type,
          fmt::format("{} is not supported and was skipped (first at {})", what, where.toString()));
    }
    reportUnused(p, what);
  }

  void areaLight(const std::string& type, const PbrtParams& p, const SourceLocation& where) {
    if (type != "diffuse") {
      p.markAllUsed();
      warnings_.once("arealight|" + type, fmt::format("AreaLightSource \"{}\" is not supported and "
                                                      "was skipped (first at {})",
                                                      type, where.toString()));
      return;
    }
    Vec3f L = materials_.constantColor(p, "L", Vec3f(1), SpectrumUse::Illuminant) * lightScale(p);
    const bool twoSided = p.getBool("twosided", false);
    if (p.has("filename")) {
      p.find("filename");
      warnings_.once("arealight image", fmt::format("AreaLightSource image emission is not "
                                                    "supported: uniform L is used (at {})",
                                                    where.toString()));
    }
    std::optional<float> power;
    if (const float watts = p.getFloat("power", -1); watts > 0) power = watts;
    reportUnused(p, "AreaLightSource \"diffuse\"");
    state_.areaLight = AreaLight{L, twoSided, power};
  }

  // ----------------------------------------------------------------- shapes

  std::vector<Vec3f> points(const PbrtParam* p) {
    std::vector<Vec3f> out;
    if (!p) return out;
    out.resize(p->floats.size() / 3);
    std::memcpy(static_cast<void*>(out.data()), p->floats.data(), out.size() * sizeof(Vec3f));
    for (size_t i = 0; i < out.size(); ++i)
      if (!isFinite(out[i])) PbrtParams::fail(*p, fmt::format("value {} is not finite", i));
    return out;
  }

  std::vector<Vec2f> uvsOf(const PbrtParams& p, size_t count, const SourceLocation& where) {
    const PbrtParam* uv = p.getArray("uv", {"float", "point2"});
    if (!uv) uv = p.getArray("st", {"float", "point2"});
    std::vector<Vec2f> out;
    if (!uv) return out;
    if (uv->floats.size() != 2 * count)
      PbrtParams::fail(*uv, fmt::format("{} values for {} vertices (two per vertex needed)",
                                        uv->floats.size(), count));
    (void)where;
    out.resize(count);
    std::memcpy(static_cast<void*>(out.data()), uv->floats.data(), count * sizeof(Vec2f));
    return out;
  }

  void shape(const std::string& type, const PbrtParams& p, const SourceLocation& where) {
    const std::string what = fmt::format("Shape \"{}\"", type);
    if (!currentObject_) checkInvertible(where);
    shapeWhere_ = where;
    // pbrt ignores the area light of a moving shape (with a warning): so does Ferry.
    struct LightAside {
      std::optional<AreaLight>& light;
      std::optional<AreaLight> kept;
      ~LightAside() {
        if (kept) light = std::move(kept);
      }
    } aside{state_.areaLight, std::nullopt};
    if (state_.areaLight && moving() && !currentObject_) {
      warnings_.once("moving light",
                     fmt::format("an area light on a moving shape is ignored, as pbrt ignores "
                                 "it (first at {})",
                                 where.toString()));
      aside.kept = std::move(state_.areaLight);
      state_.areaLight.reset();
    }
    try {
      if (type == "curve") {
        curves(p, where);
        reportUnused(p, what);
        return;
      }
      flushCurves();
      Mesh mesh;
      std::string plyPath;
      // pbrt-v4's area light "power" is per pbrt shape: the area of one (an
      // analytic shape's, in its own space as pbrt computes it), or the count
      // of triangles or patches a mesh is, each of them a shape in pbrt.
      float shapeArea = 0;
      size_t meshShapes = 0;
      if (type == "trianglemesh") {
        mesh = triangleMesh(p, where);
      } else if (type == "plymesh") {
        plyPath = resolve(p.getString("filename", ""), where, "PLY file");
      } else if (type == "bilinearmesh") {
        const PbrtParam* P = p.getArray("P", {"point3"});
        if (!P) fail(where, "bilinearmesh needs \"point3 P\"");
        std::vector<Vec3f> pos = points(P);
        std::vector<int32_t> indices;
        if (const PbrtParam* idx = p.getArray("indices", {"integer"}))
          indices = idx->ints;
        else if (pos.size() == 4)
          indices = {0, 1, 2, 3};
        else
          fail(where, "bilinearmesh needs \"integer indices\" (or exactly 4 points)");
        std::vector<Vec3f> normals = points(p.getArray("N", {"normal"}));
        if (!normals.empty() && normals.size() != pos.size())
          fail(where,
               fmt::format("bilinearmesh: {} normals for {} points", normals.size(), pos.size()));
        mesh = tessellateBilinearPatches(pos, indices, uvsOf(p, pos.size(), where), normals);
        meshShapes = indices.size() / 4;
      } else if (type == "loopsubdiv") {
        const PbrtParam* P = p.getArray("P", {"point3"});
        const PbrtParam* idx = p.getArray("indices", {"integer"});
        if (!P || !idx) fail(where, "loopsubdiv needs \"point3 P\" and \"integer indices\"");
        if (idx->ints.size() % 3 != 0)
          PbrtParams::fail(*idx,
                           fmt::format("{} indices is not a multiple of 3", idx->ints.size()));
        std::vector<Vec3i> tris(idx->ints.size() / 3);
        std::memcpy(static_cast<void*>(tris.data()), idx->ints.data(), tris.size() * sizeof(Vec3i));
        int levels = p.has("levels") ? p.getInt("levels", 3) : p.getInt("nlevels", 3);
        mesh = loopSubdivide(points(P), tris, std::max(levels, 0), options_.maxGeneratedTriangles);
      } else if (type == "sphere" || type == "disk" || type == "cylinder") {
        // pbrt's own Area() of the shape, in its object space, for "power".
        const float r = p.getFloat("radius", 1), phiMaxDegrees = p.getFloat("phimax", 360);
        const float phiMax = std::clamp(phiMaxDegrees, 0.0f, 360.0f) * kPi / 180;
        if (type == "sphere") {
          const float zMin = p.getFloat("zmin", -r), zMax = p.getFloat("zmax", r);
          mesh = tessellateSphere(r, zMin, zMax, phiMaxDegrees);
          auto clampZ = [&](float z) { return std::clamp(z, -std::abs(r), std::abs(r)); };
          shapeArea = phiMax * std::abs(r) * std::abs(clampZ(zMax) - clampZ(zMin));
        } else if (type == "disk") {
          const float ri = p.getFloat("innerradius", 0);
          mesh = tessellateDisk(p.getFloat("height", 0), r, ri, phiMaxDegrees);
          shapeArea = phiMax * 0.5f * std::abs(r * r - ri * ri);
        } else {
          const float zMin = p.getFloat("zmin", -1), zMax = p.getFloat("zmax", 1);
          mesh = tessellateCylinder(r, zMin, zMax, phiMaxDegrees);
          shapeArea = std::abs(zMax - zMin) * std::abs(r) * phiMax;
        }
      } else if (type == "cone") {
        mesh = tessellateCone(p.getFloat("radius", 1), p.getFloat("height", 1),
                              p.getFloat("phimax", 360));
      } else if (type == "paraboloid") {
        mesh = tessellateParaboloid(p.getFloat("radius", 1), p.getFloat("zmin", 0),
                                    p.getFloat("zmax", 1), p.getFloat("phimax", 360));
      } else if (type == "hyperboloid") {
        mesh = tessellateHyperboloid(p.getPoint3("p1").value_or(Vec3f(0, 0, 0)),
                                     p.getPoint3("p2").value_or(Vec3f(1, 1, 1)),
                                     p.getFloat("phimax", 360));
      } else if (type == "heightfield") {
        const PbrtParam* pz = p.getArray("Pz", {"float"});
        if (!pz) fail(where, "heightfield needs \"float Pz\"");
        mesh = tessellateHeightfield(p.getInt("nu", 0), p.getInt("nv", 0), pz->floats);
      } else {
        p.markAllUsed();
        warnings_.once("shape|" + type,
                       fmt::format("{} is not supported and was skipped (first at {})", what,
                                   where.toString()));
        return;
      }
      if (type == "trianglemesh") meshShapes = mesh.indices.size();
      MediumInterface media = shapeMedia(where);
      if (media.isTransition() && materials_.isInterface(state_.material)) {
        reportUnused(p, what);
        if (!plyPath.empty()) mesh = readPlyAt(plyPath, where);
        mesh.name = type;
        addMediumBoundary(std::move(mesh), media);
        return;
      }
      Vec3f emission = state_.areaLight ? state_.areaLight->radiance : Vec3f(0);
      if (state_.areaLight && state_.areaLight->power)
        emission *= powerScale(type, mesh, shapeArea, meshShapes, where);
      const PbrtAlpha alpha = materials_.shapeAlpha(p, dialect_ == Dialect::V3);
      materials_.setV4File(dialect_ == Dialect::V4);
      const int32_t material = materials_.materialFor(
          state_.material, emission, alpha, !state_.areaLight || state_.areaLight->twoSided,
          lightSampledOnBackSide(where));
      media = withSubsurfaceInside(media, material, where);
      if (!plyPath.empty()) {
        p.find("displacement");
        p.find("edgelength");
        if (p.has("displacement"))
          warnings_.once(
              "displacement",
              fmt::format("plymesh displacement is not supported (first at {})", where.toString()));
        reportUnused(p, what);
        addPly(plyPath, material, media, where);
        return;
      }
      reportUnused(p, what);
      if (mesh.indices.empty()) return;
      dropUselessNormals(mesh, where);
      mesh.name = type;
      mesh.material = material;
      mesh.media = media;
      addMesh(std::move(mesh));
    } catch (const InputError& e) {
      if (!e.where().file.empty()) throw;
      throw InputError(where, fmt::format("{}: {}", what, e.what()));
    }
  }

  // What the area light's radiance is multiplied by for its "power"
  // (pbrt-v4's DiffuseAreaLight::Create): power / (sides x area x pi), the
  // area one pbrt shape's: `shapeArea` for an analytic shape, else the mean
  // world-space area of the mesh's `meshShapes` triangles or patches. pbrt
  // gives each of those the power; Ferry one radiance to the mesh, the same
  // total power, which is pbrt's exactly when their areas are equal (else a
  // warning says so).
  float powerScale(const std::string& type, const Mesh& mesh, float shapeArea, size_t meshShapes,
                   const SourceLocation& where) {
    const AreaLight& light = *state_.areaLight;
    const float sides = light.twoSided ? 2.0f : 1.0f;
    if (shapeArea > 0) return *light.power / (sides * shapeArea * kPi);
    if (meshShapes == 0 || mesh.indices.empty()) {
      warnings_.once("area power|" + type,
                     fmt::format("AreaLightSource \"float power\" is not applied to Shape \"{}\" "
                                 "(its radiance is used as given; first at {})",
                                 type, where.toString()));
      return 1;
    }
    double total = 0;
    float smallest = std::numeric_limits<float>::max(), largest = 0;
    for (const Vec3i& t : mesh.indices) {
      const Vec3f a = state_.ctm.transformPoint(mesh.positions[size_t(t.x)]);
      const Vec3f b = state_.ctm.transformPoint(mesh.positions[size_t(t.y)]);
      const Vec3f c = state_.ctm.transformPoint(mesh.positions[size_t(t.z)]);
      const float area = 0.5f * length(cross(b - a, c - a));
      total += area;
      smallest = std::min(smallest, area);
      largest = std::max(largest, area);
    }
    const double mean = total / double(meshShapes);
    if (!(mean > 0)) return 1;
    // (A bilinear mesh's patches are not told apart after tessellation.)
    const bool unequal = type == "trianglemesh" ? largest > smallest * 1.001f : meshShapes > 1;
    if (unequal)
      warnings_.once("area power unequal",
                     fmt::format("AreaLightSource \"float power\" on a Shape \"{}\" of {} "
                                 "pieces: pbrt-v4 gives each piece that power, Ferry the whole "
                                 "mesh the same total at one radiance, which differs where the "
                                 "pieces' areas do (first at {})",
                                 type, meshShapes, where.toString()));
    return float(*light.power / (sides * mean * kPi));
  }

  Mesh triangleMesh(const PbrtParams& p, const SourceLocation& where) {
    const PbrtParam* P = p.getArray("P", {"point3"});
    if (!P) fail(where, "trianglemesh needs \"point3 P\"");
    Mesh m;
    m.positions = points(P);
    const PbrtParam* idx = p.getArray("indices", {"integer"});
    std::vector<int32_t> indices;
    if (idx) {
      if (idx->ints.size() % 3 != 0)
        PbrtParams::fail(*idx, fmt::format("{} indices is not a multiple of 3", idx->ints.size()));
      for (size_t i = 0; i < idx->ints.size(); ++i)
        if (idx->ints[i] < 0 || size_t(idx->ints[i]) >= m.positions.size())
          PbrtParams::fail(*idx, fmt::format("index {} (entry {}) is out of range: {} points",
                                             idx->ints[i], i, m.positions.size()));
      m.indices.resize(idx->ints.size() / 3);
      std::memcpy(static_cast<void*>(m.indices.data()), idx->ints.data(),
                  m.indices.size() * sizeof(Vec3i));
    } else if (m.positions.size() == 3) {
      m.indices.push_back({0, 1, 2});
    } else {
      fail(where, "trianglemesh needs \"integer indices\" (or exactly 3 points)");
    }
    if (const PbrtParam* N = p.getArray("N", {"normal"})) {
      m.normals = points(N);
      if (m.normals.size() != m.positions.size())
        PbrtParams::fail(
            *N, fmt::format("{} normals for {} points", m.normals.size(), m.positions.size()));
    }
    m.uvs = uvsOf(p, m.positions.size(), where);
    p.find("S");  // tangents: Ferry makes its own frames
    p.find("faceIndices");
    return m;
  }

  void curves(const PbrtParams& p, const SourceLocation& where) {
    if (state_.areaLight && state_.areaLight->power)
      warnings_.once("area power|curves",
                     fmt::format("AreaLightSource \"float power\" is not applied to Shape "
                                 "\"curve\" (its radiance is used as given; first at {})",
                                 where.toString()));
    CurveDescription c;
    const PbrtParam* P = p.getArray("P", {"point3"});
    if (!P) fail(where, "curves needs \"point3 P\"");
    c.points = points(P);
    c.degree = p.getInt("degree", 3);
    std::string basis = p.getString("basis", "bezier");
    if (basis == "bezier")
      c.basis = CurveBasis::Bezier;
    else if (basis == "bspline")
      c.basis = CurveBasis::BSpline;
    else
      fail(where, fmt::format("curves: unknown basis \"{}\" (bezier, bspline)", basis));
    std::string type = p.getString("type", "flat");
    if (!parseCurveType(type, c.type))
      fail(where, fmt::format("curves: unknown type \"{}\" (flat, cylinder, ribbon)", type));
    float width = p.getFloat("width", 1);
    c.width0 = p.getFloat("width0", width);
    c.width1 = p.getFloat("width1", width);
    c.normals = points(p.getArray("N", {"normal"}));
    c.splitDepth = p.getInt("splitdepth", 3);
    const PbrtAlpha alpha = materials_.shapeAlpha(p, dialect_ == Dialect::V3);
    const int32_t material = materials_.materialFor(
        state_.material, state_.areaLight ? state_.areaLight->radiance : Vec3f(0), alpha,
        !state_.areaLight || state_.areaLight->twoSided, lightSampledOnBackSide(where));
    // Consecutive curves with the same material, type and transform share a shape.
    const bool reuse = curveBatch_ && curveBatch_->material == material &&
                       curveBatch_->object == currentObject_.value_or(-1) &&
                       curveBatch_->type == c.type && sameTransform(curveBatch_->ctm, state_.ctm) &&
                       sameTransform(curveBatch_->ctmEnd, state_.ctmEnd) &&
                       curveBatch_->motion == placedMotion(where) &&
                       curveBatch_->segments.size() < (size_t(1) << 24);
    if (!reuse) {
      flushCurves();
      if (currentObject_ && moving()) checkEndInvertible(where);
      curveBatch_ = CurveBatch{material,      currentObject_.value_or(-1), c.type, state_.ctm,
                               state_.ctmEnd, placedMotion(where),         {},     {}};
    }
    // In an object, a still transform is baked; a moving one makes the
    // curves a part of their own in their own space (flushCurves).
    if (currentObject_ && !moving() && !sameTransform(state_.ctm, Affine3f::identity())) {
      // In an object, the transform is baked: points and normals moved,
      // widths scaled by the transform's mean scale.
      const float scale = std::cbrt(std::abs(state_.ctm.determinant()));
      for (Vec3f& q : c.points) q = state_.ctm.transformPoint(q);
      for (Vec3f& n : c.normals) n = state_.ctm.transformNormal(n);
      c.width0 *= scale;
      c.width1 *= scale;
    }
    try {
      appendCurveSegments(c, curveBatch_->segments, curveBatch_->normals);
    } catch (const InputError& e) {
      fail(where, e.what());
    }
  }

  // The curves gathered so far become one geometry (one object with one
  // instance at the top level; the current object's otherwise).
  void flushCurves() {
    if (!curveBatch_) return;
    CurveBatch batch = std::move(*curveBatch_);
    curveBatch_.reset();
    if (batch.segments.empty()) return;
    Geometry g;
    g.name = "curves";
    g.material = batch.material;
    g.shape =
        std::make_shared<Curves>(batch.type, std::move(batch.segments), std::move(batch.normals));
    scene_.geometries.push_back(std::move(g));
    const auto index = int32_t(scene_.geometries.size() - 1);
    const bool movingPart = batch.object >= 0 && !sameTransform(batch.ctm, batch.ctmEnd);
    if (batch.object >= 0 && !movingPart) {
      scene_.objects[size_t(batch.object)].geometries.push_back(index);
      return;
    }
    if (movingPart) {
      // Moving inside ObjectBegin: an object of its own, which each instance
      // of the definition places moving (objectInstance).
      Object part;
      part.name = "curves";
      part.geometries.push_back(index);
      scene_.objects.push_back(std::move(part));
      movingParts_[batch.object].push_back(
          {int32_t(scene_.objects.size() - 1), batch.ctm, batch.ctmEnd});
      return;
    }
    Object o;
    o.name = "curves";
    o.geometries.push_back(index);
    scene_.objects.push_back(std::move(o));
    scene_.instances.push_back({int32_t(scene_.objects.size() - 1), batch.ctm, batch.motion});
  }

  static void bake(Mesh& mesh, const Affine3f& t) {
    for (Vec3f& p : mesh.positions) p = t.transformPoint(p);
    if (!mesh.normals.empty()) {
      Affine3f inv = t.inverse();
      for (Vec3f& n : mesh.normals) {
        Vec3f m{inv.l[0][0] * n.x + inv.l[1][0] * n.y + inv.l[2][0] * n.z,
                inv.l[0][1] * n.x + inv.l[1][1] * n.y + inv.l[2][1] * n.z,
                inv.l[0][2] * n.x + inv.l[1][2] * n.y + inv.l[2][2] * n.z};
        float len = length(m);
        n = len > 0 && std::isfinite(len) ? m / len : Vec3f(0, 0, 1);
      }
    }
  }

  // Adds a mesh where it belongs: into the object being defined (in the
  // definition's space), or as a new object placed by one instance.
  // A one-sided emitter emits on the side of pbrt's surface normal: the
  // world winding normal flipped by ReverseOrientation and by a transform
  // that swaps handedness, or (with vertex normals) turned to the normals'
  // side. Ferry's emitting side is the object's winding normal transformed
  // as a normal (render/surface.h; the handedness flip is already in that),
  // so the winding is set here: reversed under ReverseOrientation, or turned
  // triangle by triangle to its vertex normals.
  // A mesh that bounds media is oriented the same way (its outside is on
  // pbrt's normal's side).
  // pbrt-v3 under a mirror (Material::lightSampledOnBackSide) sees the
  // emitting side with vertex normals on the normals' side turned by
  // ReverseOrientation XOR the mirror (its shading normal's flip), while it
  // samples light leaving the side the normals (turned by
  // ReverseOrientation) face; without normals it sees the side pbrt-v4 does.
  void orientEmitter(Mesh& mesh) const {
    const Material& material = scene_.materials[size_t(mesh.material)];
    if ((!material.isEmissive() || material.emitsBackSide) && !mesh.media.isTransition()) return;
    orientToPbrtNormal(mesh, material.lightSampledOnBackSide && !state_.reverseOrientation);
  }
  // pbrt-v3 reads a tabulated BSDF whose sides differ (FourierBsdfTable::
  // sided) in its shading frame: with vertex normals, the normals turned by
  // ReverseOrientation XOR a handedness swap (Triangle::Intersect and
  // SetShadingGeometry); without, the winding normal turned by
  // ReverseOrientation (as seen after the transform). Ferry's frame is the
  // mesh's normals (or winding): a v3 mesh of such a material gets them
  // turned so, its winding following its normals.
  void orientSidedSurface(Mesh& mesh) const {
    if (dialect_ != Dialect::V3 || currentObject_ || mesh.media.isTransition()) return;
    const Material& material = scene_.materials[size_t(mesh.material)];
    const int32_t table = material.bsdfTable();
    if (table < 0 || size_t(table) >= scene_.bsdfTables.size() ||
        !scene_.bsdfTables[size_t(table)]->sided())
      return;
    if (material.isEmissive() && !material.emitsBackSide) return;  // oriented as an emitter
    if (mesh.normals.empty()) {
      if (state_.reverseOrientation)
        for (Vec3i& tri : mesh.indices) std::swap(tri.y, tri.z);
      return;
    }
    if (state_.reverseOrientation != (state_.ctm.determinant() < 0))
      for (size_t i = 0; i < mesh.normals.size(); ++i) mesh.normals[i] = -mesh.normals[i];
    orientToPbrtNormal(mesh);
  }

  // `againstNormals`: with vertex normals, the winding faces away from them.
  void orientToPbrtNormal(Mesh& mesh, bool againstNormals = false) const {
    for (Vec3i& tri : mesh.indices) {
      bool flip = state_.reverseOrientation;
      if (!mesh.normals.empty()) {
        const Vec3f& a = mesh.positions[size_t(tri.x)];
        const Vec3f winding =
            cross(mesh.positions[size_t(tri.y)] - a, mesh.positions[size_t(tri.z)] - a);
        const Vec3f normal =
            mesh.normals[size_t(tri.x)] + mesh.normals[size_t(tri.y)] + mesh.normals[size_t(tri.z)];
        flip = (dot(winding, normal) < 0) != againstNormals;
      }
      if (flip) std::swap(tri.y, tri.z);
    }
  }

  // Whether the shapes that follow are pbrt-v3 one-sided area lights under a
  // transform that swaps handedness: pbrt-v3 samples their light leaving the
  // side opposite to the one a ray sees emitting (its Triangle::Sample turns
  // the normal by ReverseOrientation alone, its Intersect by ReverseOrientation
  // XOR the handedness swap); Ferry keeps that (Material::lightSampledOnBackSide).
  bool lightSampledOnBackSide(const SourceLocation& where) {
    if (dialect_ != Dialect::V3 || !state_.areaLight || state_.areaLight->twoSided ||
        currentObject_ || !(state_.ctm.determinant() < 0))
      return false;
    warnings_.once("v3 mirrored emitter",
                   fmt::format("pbrt-v3 scene: a one-sided area light under a transform that "
                               "swaps handedness emits as pbrt-v3 has it: its light is sampled "
                               "leaving the side opposite to the one a ray sees emitting (first "
                               "at {})",
                               where.toString()));
    return true;
  }

  void noteDialect(Dialect d) {
    if (dialect_ == Dialect::Unknown) dialect_ = d;
  }
  void noteMaterialDialect(const std::string& type) {
    static const std::set<std::string> v3{"matte",       "plastic", "uber",         "substrate",
                                          "translucent", "fourier", "kdsubsurface", "mirror",
                                          "glass",       "metal",   "disney"};
    static const std::set<std::string> v4{
        "diffuse",    "coateddiffuse",  "coatedconductor",     "conductor",
        "dielectric", "thindielectric", "diffusetransmission", "measured"};
    if (v3.count(type)) noteDialect(Dialect::V3);
    if (v4.count(type)) noteDialect(Dialect::V4);
  }

  // The media a shape bounds: none inside an object definition (pbrt does
  // not place media with instances either).
  MediumInterface shapeMedia(const SourceLocation& where) {
    const MediumInterface media = currentMedia(where);
    if (currentObject_ && media.isTransition()) {
      warnings_.once("instanced media",
                     fmt::format("a MediumInterface inside ObjectBegin is ignored: instanced "
                                 "shapes bound no media (first at {})",
                                 where.toString()));
      return {};
    }
    return media;
  }

  // A shape of a subsurface material encloses its medium (none inside an
  // object definition: instanced shapes bound no media).
  MediumInterface withSubsurfaceInside(MediumInterface media, int32_t material,
                                       const SourceLocation& where) {
    const int32_t inside = materials_.interiorMedium(material);
    if (inside == kNoMedium) return media;
    if (currentObject_) {
      warnings_.once(
          "instanced subsurface",
          fmt::format("a subsurface material inside ObjectBegin has no medium "
                      "behind its surface: when walked (the subsurface setting), light that enters "
                      "passes through (first at {})",
                      where.toString()));
      return media;
    }
    media.inside = inside;
    return media;
  }

  // A shape that only bounds media (Material "" or "interface"): oriented
  // as pbrt orients its normal (the outside), in world space.
  void addMediumBoundary(Mesh mesh, const MediumInterface& media) {
    if (mesh.indices.empty()) return;
    if (moving())
      warnings_.once("moving boundary",
                     fmt::format("a moving medium boundary is not supported: it stays at its "
                                 "start transform (first at {})",
                                 shapeWhere_.toString()));
    orientToPbrtNormal(mesh);
    bake(mesh, state_.ctm);
    // Baking through a mirror turns the winding's normal around.
    if (state_.ctm.determinant() < 0)
      for (Vec3i& tri : mesh.indices) std::swap(tri.y, tri.z);
    mesh.normals.clear();
    mesh.uvs.clear();
    mesh.material = 0;
    scene_.mediumBoundaries.push_back({std::move(mesh), media});
  }

  // Out-of-core loading (LoadOptions::meshStore): the meshes finished so far
  // go to the store, so a scene of many plymesh files is never all in
  // memory; the current curve batch, still growing, stays until a later
  // shape ends it (loadScene stores what is left at the end).
  void storeFinishedMeshes() {
    if (!options_.meshStore) return;
    for (; storedUpTo_ < scene_.meshes.size(); ++storedUpTo_) {
      options_.meshStore->store(scene_.meshes[storedUpTo_]);
    }
  }

  int32_t addMesh(Mesh mesh) {
    storeFinishedMeshes();
    orientEmitter(mesh);
    orientSidedSurface(mesh);
    if (currentObject_ && moving()) {
      // Motion inside ObjectBegin: the mesh is an object of its own, which
      // each instance of this one places moving (objectInstance).
      checkEndInvertible(shapeWhere_);
      scene_.meshes.push_back(std::move(mesh));
      const int32_t index = int32_t(scene_.meshes.size() - 1);
      Object part;
      part.name = scene_.meshes.back().name;
      part.meshes.push_back(index);
      scene_.objects.push_back(std::move(part));
      movingParts_[*currentObject_].push_back(
          {int32_t(scene_.objects.size() - 1), state_.ctm, state_.ctmEnd});
      return index;
    }
    if (currentObject_) {
      if (!sameTransform(state_.ctm, Affine3f::identity())) bake(mesh, state_.ctm);
      scene_.meshes.push_back(std::move(mesh));
      int32_t index = int32_t(scene_.meshes.size() - 1);
      scene_.objects[size_t(*currentObject_)].meshes.push_back(index);
      return index;
    }
    scene_.meshes.push_back(std::move(mesh));
    int32_t index = int32_t(scene_.meshes.size() - 1);
    Object o;
    o.name = scene_.meshes.back().name;
    o.meshes.push_back(index);
    scene_.objects.push_back(std::move(o));
    scene_.instances.push_back(
        {int32_t(scene_.objects.size() - 1), state_.ctm, placedMotion(shapeWhere_)});
    return index;
  }

  void addPly(const std::string& path, int32_t material, const MediumInterface& media,
              const SourceLocation& where) {
    // A one-sided emitter's winding depends on ReverseOrientation and the
    // transform's handedness (orientEmitter): meshes differing in those are not shared.
    const int orientation =
        (state_.reverseOrientation ? 1 : 0) | (state_.ctm.determinant() < 0 ? 2 : 0);
    if (!currentObject_) {
      auto key = std::make_tuple(path, material, orientation, media.inside, media.outside);
      auto it = topLevelPly_.find(key);
      if (it != topLevelPly_.end()) {
        scene_.instances.push_back({it->second, state_.ctm, placedMotion(where)});
        return;
      }
      Mesh mesh = readPlyAt(path, where);
      mesh.material = material;
      mesh.media = media;
      addMesh(std::move(mesh));
      topLevelPly_.emplace(key, int32_t(scene_.objects.size() - 1));
      return;
    }
    // Inside an object the mesh is baked with the current transform; the
    // same file, material and transform share one mesh.
    std::string key = fmt::format("{}|{}|{}|", path, material, orientation);
    key.append(reinterpret_cast<const char*>(&state_.ctm), sizeof(Affine3f));
    auto it = objectPly_.find(key);
    if (it != objectPly_.end() && !moving()) {
      scene_.objects[size_t(*currentObject_)].meshes.push_back(it->second);
      return;
    }
    Mesh mesh = readPlyAt(path, where);
    mesh.material = material;
    mesh.media = media;
    const bool movingPart = moving();
    const int32_t added = addMesh(std::move(mesh));
    if (!movingPart) objectPly_.emplace(key, added);
  }

  Mesh readPlyAt(const std::string& path, const SourceLocation& where) {
    Mesh mesh;
    try {
      mesh = readPly(path, options_);
    } catch (const InputError& e) {
      throw InputError(where, fmt::format("plymesh: {}", e.what()));
    }
    dropUselessNormals(mesh, where);
    return mesh;
  }

  void dropUselessNormals(Mesh& mesh, const SourceLocation& where) {
    if (!normalsPerpendicularToFaces(mesh)) return;
    warnings_.once("perpendicular normals|" + where.toString(),
                   fmt::format("{}: the shape's normals all lie in its faces' planes (they carry "
                               "no shading information): ignored, the faces' own normals are used",
                               where.toString()));
    mesh.normals.clear();
  }

  // ----------------------------------------------------------------- finish

  // pbrt-v3's spots fall off as a quartic, pbrt-v4's as a smoothstep.
  void setSpotFalloff() {
    if (dialect_ != Dialect::V3) return;
    for (PointLight& l : scene_.pointLights)
      if (l.falloff == PointLight::Falloff::SmoothStep) l.falloff = PointLight::Falloff::Quartic;
  }

  void makeEnvironment() {
    Vec3f constant(0);
    std::shared_ptr<HdrImage> image;
    for (const InfiniteLight& light : infiniteLights_) {
      const PbrtParams& p = light.params;
      const std::string what = "LightSource \"infinite\"";
      Vec3f L = materials_.constantColor(p, "L", Vec3f(1), SpectrumUse::Illuminant) * lightScale(p);
      std::string map = p.getString("mapname", "");
      bool v4map = false;
      if (map.empty()) {
        map = p.getString("filename", "");
        v4map = !map.empty();
      }
      if (const PbrtParam* portal = p.find("portal"); portal)
        warnings_.once("portal", fmt::format("infinite light portals are ignored (at {})",
                                             light.where.toString()));
      p.find("samples");
      if (map.empty()) {
        if (p.has("illuminance")) {
          float e = p.getFloat("illuminance", 1);
          float y = luminance(L);
          // A constant sky of radiance L gives illuminance pi L on an upward surface.
          if (y > 0) L = L * (e / (kPi * y));
        }
        constant += L;
        reportUnused(p, what);
        continue;
      }
      if (p.has("illuminance")) {
        p.find("illuminance");
        warnings_.once("illuminance map", fmt::format("\"illuminance\" of an image infinite light "
                                                      "is ignored (at {})",
                                                      light.where.toString()));
      }
      reportUnused(p, what);
      std::string lookedFor;
      std::optional<std::string> found = tryResolve(map, lookedFor);
      if (!found) {
        if (!options_.envFallback)
          throw InputError(light.where,
                           fmt::format("environment map \"{}\" not found (looked for {}); set "
                                       "env-fallback to use a constant white environment "
                                       "instead",
                                       map, lookedFor));
        warnings_.once("env fallback|" + map,
                       fmt::format("{}: environment map \"{}\" not found: using a constant "
                                   "environment ({}) instead (env-fallback)",
                                   light.where.toString(), map, average3(L)));
        constant += L;
        continue;
      }
      const std::string path = *found;
      if (image) {
        warnings_.once("two maps", fmt::format("only one environment image is supported: \"{}\" "
                                               "is ignored (at {})",
                                               map, light.where.toString()));
        continue;
      }
      HdrImage source;
      try {
        source = readHdrImage(path);
      } catch (const InputError& e) {
        throw InputError(light.where, fmt::format("environment map: {}", e.what()));
      }
      bool square = source.width == source.height;
      image = std::make_shared<HdrImage>(
          resampleEnvironment(source, light.lightFromWorld, v4map && square, L));
    }
    if (image) {
      if (maxComponent(constant) > 0)
        for (Vec3f& px : image->pixels) px += constant;
      scene_.environment.image = image;
      scene_.environment.color = Vec3f(1);
    } else {
      scene_.environment.color = constant;
    }
  }

  static std::string average3(Vec3f c) {
    return fmt::format("{:.3g} {:.3g} {:.3g}", c.x, c.y, c.z);
  }

  // Ferry's environment: lat-long, y up, row 0 at +y, u = atan2(z, x) / 2 pi.
  HdrImage resampleEnvironment(const HdrImage& source, const Affine3f& lightFromWorld,
                               bool equalArea, Vec3f scale) {
    HdrImage out;
    out.name = source.name;
    out.width = equalArea ? 2 * source.width : source.width;
    out.height = equalArea ? source.height : source.height;
    out.pixels.resize(size_t(out.width) * out.height);
    for (int y = 0; y < out.height; ++y) {
      float theta = kPi * (y + 0.5f) / out.height;
      for (int x = 0; x < out.width; ++x) {
        float phi = 2 * kPi * (x + 0.5f) / out.width;
        Vec3f d(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
        Vec3f l = lightFromWorld.transformVector(d);
        float len = length(l);
        l = len > 0 ? l / len : Vec3f(0, 0, 1);
        Vec3f c;
        if (equalArea) {
          Vec2f uv = equalAreaSphereToSquare(l);
          c = bilinear(source, uv.x * source.width - 0.5f, uv.y * source.height - 0.5f, false);
        } else {
          float t = std::acos(std::clamp(l.z, -1.0f, 1.0f));
          float p = std::atan2(l.y, l.x);
          if (p < 0) p += 2 * kPi;
          c = bilinear(source, p / (2 * kPi) * source.width - 0.5f, t / kPi * source.height - 0.5f,
                       true);
        }
        out.pixels[size_t(y) * out.width + x] = c * scale;
      }
    }
    return out;
  }

  void makeCamera() {
    CameraView view;
    view.name = "camera";
    CameraDefinition c = camera_.value_or(CameraDefinition{});
    float det = c.cameraFromWorld.determinant();
    if (!std::isfinite(det) || det == 0) fail(c.where, "Camera: the camera transform is singular");
    Affine3f worldFromCamera = c.cameraFromWorld.inverse();
    Vec3f from = worldFromCamera.transformPoint(Vec3f(0));
    Vec3f forward = worldFromCamera.transformVector({0, 0, 1});
    Vec3f up = worldFromCamera.transformVector({0, 1, 0});
    Vec3f right = worldFromCamera.transformVector({1, 0, 0});
    if (!(length(forward) > 0) || !(length(up) > 0))
      fail(c.where, "Camera: degenerate camera transform");
    view.from = from;
    view.at = from + normalize(forward);
    view.up = normalize(up);
    view.leftHanded = dot(right, cross(forward, up)) < 0;
    // pbrt's fov spans the shorter image side.
    float w = float(filmWidth_), h = float(filmHeight_);
    float half = std::tan(radians(c.fov) / 2);
    view.fovY = w < h ? 2 * std::atan(half * h / w) * 180 / kPi : c.fov;
    // The lens lies across the view axis, the focal plane along it: camera
    // space lengths scaled as the camera transform scales those axes.
    view.lensRadius = c.lensRadius * length(right);
    view.focalDistance = c.focalDistance * length(forward);
    view.motion = c.motion;
    scene_.views.push_back(view);
    scene_.shutterOpen = c.shutterOpen;
    scene_.shutterClose = c.shutterClose;
    // pbrt-v4's sensor integrates over the exposure (its imaging ratio is
    // the exposure time x ISO / 100); pbrt-v3's film does not.
    if (dialect_ == Dialect::V4) {
      const float exposure = c.shutterClose - c.shutterOpen;
      if (!(exposure > 0))
        fail(c.where, "Camera: the shutter never opens (shutterclose equals shutteropen)");
      scene_.filmScale *= exposure;
    }
  }

  const LoadOptions& options_;
  LoadWarnings warnings_;
  std::string mainDirectory_;
  Scene scene_;
  PbrtMaterials materials_;
  std::map<std::string, int32_t> namedMedia_;  // kNoMedium: defined, but not supported
  std::vector<std::unique_ptr<Input>> inputs_;
  std::vector<Block> blocks_;
  GraphicsState state_;
  bool activeStart_ = true;
  bool activeEnd_ = true;
  bool inWorld_ = false;
  Dialect dialect_ = Dialect::Unknown;
  bool ended_ = false;
  std::map<std::string, std::pair<Affine3f, Affine3f>> coordinateSystems_;  // start, end
  SourceLocation shapeWhere_;                                               // the shape being read
  // pbrt-v3's shapes moving inside an object definition, by object: each
  // an object of its own with its motion in the object's space.
  struct MovingPart {
    int32_t object;
    Affine3f start, end;
  };
  std::map<int32_t, std::vector<MovingPart>> movingParts_;
  struct MovingObjectInstance {
    size_t instance;
    Affine3f start, end;
  };
  std::vector<MovingObjectInstance> movingObjectInstances_;
  // Each instance of a moving part, and what it was made from.
  struct MovingPartInstance {
    size_t instance;
    Affine3f start, end, partStart, partEnd;
  };
  std::vector<MovingPartInstance> movingPartInstances_;
  // The last motion made, shared by what is placed under the same transforms.
  std::shared_ptr<const InstanceMotion> lastMotion_;
  Affine3f lastMotionFrom_, lastMotionTo_;
  std::map<std::string, int32_t> objects_;
  std::optional<int32_t> currentObject_;
  std::map<std::tuple<std::string, int32_t, int, int32_t, int32_t>, int32_t> topLevelPly_;
  std::map<std::string, int32_t> objectPly_;
  struct CurveBatch {
    int32_t material, object;
    CurveType type;
    Affine3f ctm, ctmEnd;
    std::shared_ptr<const InstanceMotion> motion;
    std::vector<CurveSegment> segments;
    std::vector<CurveNormals> normals;
  };
  std::optional<CurveBatch> curveBatch_;
  size_t storedUpTo_ = 0;  // meshes below this index went to options_.meshStore
  std::optional<CameraDefinition> camera_;
  int filmWidth_ = 1280, filmHeight_ = 720;
  std::vector<InfiniteLight> infiniteLights_;
};

}  // namespace

Scene loadPbrt(const std::string& path, const LoadOptions& options) {
  fs::path p(path);
  std::string dir = p.parent_path().empty() ? "." : p.parent_path().string();
  Parser parser(dir, options);
  parser.pushFile(path, SourceLocation{}, false);
  parser.run();
  return parser.finish(p.stem().string());
}

Scene loadPbrtFromString(std::string_view text, const std::string& name,
                         const std::string& directory, const LoadOptions& options) {
  Parser parser(directory, options);
  parser.pushStream(ByteStream::fromMemory(text, name), name, false, SourceLocation{});
  parser.run();
  return parser.finish(name);
}

}  // namespace ferry
