#include "io/gltf/gltf_loader.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <type_traits>

#include <fmt/format.h>
#include <stb/stb_image.h>

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/default_lighting.h"
#include "io/gltf/gltf_config.h"
#include "io/gltf/gltf_material_values.h"
#include "io/gltf/gltf_specular_layers.h"
#include "io/images/image_io.h"
#include "io/light_emitters.h"
#include "material/metallic_roughness.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;
constexpr uint32_t kChunkBin = 0x004E4942;
constexpr const char* kGlbBinaryMarker = "ferry-glb-binary-chunk.bin";
constexpr uint64_t kMaxImagePixels = uint64_t(1) << 28;
constexpr uint64_t kMaxJsonBytes = uint64_t(1) << 30;
constexpr int kEmissionLevels = 15;
// Material extensions Ferry reads (the others are ignored with a warning).
const std::set<std::string> kMaterialExtensions = {
    "KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior",
    "KHR_materials_specular", "KHR_materials_clearcoat"};

std::string urlDecode(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%' && i + 2 < s.size() && std::isxdigit(static_cast<unsigned char>(s[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(s[i + 2]))) {
      out.push_back(char(std::stoi(s.substr(i + 1, 2), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(s[i]);
    }
  }
  return out;
}

// ---------------------------------------------------------------- file access

// tinygltf reads whole files through these; ours read into the buffer it
// gives (no second copy), report progress, and serve a .glb's binary chunk
// under a marker name.
struct FileAccess {
  const LoadOptions* options = nullptr;
  std::string glbPath;
  uint64_t binOffset = 0, binLength = 0;  // of the wanted bytes of the BIN chunk
  bool hasBin = false;
};

bool isMarker(const std::string& path) {
  return fs::path(path).filename() == kGlbBinaryMarker;
}

bool fileExists(const std::string& path, void* user) {
  auto* access = static_cast<FileAccess*>(user);
  if (isMarker(path)) return access->hasBin;
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

std::string expandFilePath(const std::string& path, void*) {
  return path;
}

bool readRange(std::vector<unsigned char>* out, std::string* err, const std::string& path,
               uint64_t offset, uint64_t length, const LoadOptions& options) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) {
    *err = fmt::format("cannot open {}: {}", path, std::strerror(errno));
    return false;
  }
  if (offset > 0 && std::fseek(f.get(), long(offset), SEEK_SET) != 0) {
    *err = fmt::format("cannot seek in {}", path);
    return false;
  }
  out->resize(size_t(length));
  LoadProgress progress(options, path, length);
  uint64_t done = 0;
  while (done < length) {
    size_t chunk = size_t(std::min<uint64_t>(length - done, uint64_t(16) << 20));
    size_t n = std::fread(out->data() + done, 1, chunk, f.get());
    if (n == 0) {
      *err =
          fmt::format("{}: file ends after {} of {} bytes", path, offset + done, offset + length);
      return false;
    }
    done += n;
    progress.update(done);
  }
  progress.finish();
  return true;
}

bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                   void* user) {
  auto* access = static_cast<FileAccess*>(user);
  if (isMarker(path)) {
    if (!access->hasBin) {
      *err = "the .glb has no binary chunk";
      return false;
    }
    return readRange(out, err, access->glbPath, access->binOffset, access->binLength,
                     *access->options);
  }
  std::error_code ec;
  uint64_t size = fs::file_size(path, ec);
  if (ec) {
    *err = fmt::format("cannot read {}: {}", path, ec.message());
    return false;
  }
  return readRange(out, err, path, 0, size, *access->options);
}

bool writeWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&,
                    void*) {
  *err = "Ferry does not write glTF files";
  return false;
}

// Keeps the encoded bytes of data-URI images; buffer-view and external images
// are decoded later, and only if a material uses them.
bool keepEncodedImage(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  if (image->bufferView >= 0) return true;
  image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

uint32_t readLe32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// ------------------------------------------------------------------- parsing

tinygltf::Model parseModel(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(fmt::format("{}: no such file", path));
  const uint64_t fileSize = fs::file_size(path, ec);
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  std::string baseDir = fs::path(path).parent_path().string();
  if (baseDir.empty()) baseDir = ".";

  FileAccess access;
  access.options = &options;
  access.glbPath = path;
  std::string json;
  ByteStream in = ByteStream::openFile(path);
  if (ext == ".glb") {
    unsigned char header[20];
    if (in.read(header, 20) != 20)
      throw InputError(fmt::format("{}: too short for a .glb file", path));
    if (readLe32(header) != kGlbMagic)
      throw InputError(fmt::format("{}: not a .glb file (no glTF magic)", path));
    if (readLe32(header + 4) != 2)
      throw InputError(
          fmt::format("{}: .glb version {} (only 2 is supported)", path, readLe32(header + 4)));
    uint64_t total = readLe32(header + 8);
    if (total > fileSize)
      throw InputError(fmt::format("{}: header says {} bytes, the file has {}: truncated?", path,
                                   total, fileSize));
    uint64_t jsonLength = readLe32(header + 12);
    if (readLe32(header + 16) != kChunkJson)
      throw InputError(fmt::format("{}: the first chunk is not JSON", path));
    if (20 + jsonLength > total)
      throw InputError(fmt::format("{}: JSON chunk of {} bytes goes past the end ({} bytes)", path,
                                   jsonLength, total));
    json.resize(size_t(jsonLength));
    if (in.read(json.data(), json.size()) != json.size())
      throw InputError(fmt::format("{}: file ends inside the JSON chunk", path));
    uint64_t next = 20 + jsonLength;
    next = (next + 3) & ~uint64_t(3);
    if (next + 8 <= total) {
      in.skip(next - in.offset());
      unsigned char chunk[8];
      if (in.read(chunk, 8) != 8)
        throw InputError(fmt::format("{}: file ends inside a chunk header", path));
      uint64_t binLength = readLe32(chunk);
      if (readLe32(chunk + 4) == kChunkBin) {
        if (next + 8 + binLength > total)
          throw InputError(fmt::format("{}: binary chunk of {} bytes goes past the end ({} bytes)",
                                       path, binLength, total));
        access.hasBin = true;
        access.binOffset = next + 8;
        access.binLength = binLength;
      }
    }
    // Point buffer 0 (the binary chunk) at the marker the file callbacks serve.
    nlohmann::json doc;
    try {
      doc = nlohmann::json::parse(json);
    } catch (const std::exception& e) {
      throw InputError(fmt::format("{}: JSON chunk: {}", path, e.what()));
    }
    if (doc.is_object() && doc.contains("buffers") && doc["buffers"].is_array() &&
        !doc["buffers"].empty() && doc["buffers"][0].is_object() &&
        !doc["buffers"][0].contains("uri")) {
      if (!access.hasBin)
        throw InputError(
            fmt::format("{}: buffer 0 has no uri and the file has no binary chunk", path));
      auto& buffer = doc["buffers"][0];
      if (buffer.contains("byteLength") && buffer["byteLength"].is_number_unsigned()) {
        uint64_t wanted = buffer["byteLength"].get<uint64_t>();
        if (wanted > access.binLength)
          throw InputError(fmt::format("{}: buffer 0 claims {} bytes, the binary chunk has {}",
                                       path, wanted, access.binLength));
        access.binLength = wanted;
      }
      buffer["uri"] = kGlbBinaryMarker;
    }
    json = doc.dump();
  } else {
    if (fileSize > kMaxJsonBytes)
      throw InputError(fmt::format("{}: {} bytes of JSON is too large", path, fileSize));
    json.resize(size_t(fileSize));
    if (in.read(json.data(), json.size()) != json.size())
      throw InputError(fmt::format("{}: read error", path));
  }
  if (json.size() > UINT32_MAX) throw InputError(fmt::format("{}: JSON too large", path));

  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&fileExists, &expandFilePath, &readWholeFile, &writeWholeFile, &access});
  loader.SetImageLoader(&keepEncodedImage, nullptr);
  // Material and texture-reference extensions are read from their JSON
  // (io/gltf/gltf_material_values.h says why).
  loader.SetStoreOriginalJSONForExtrasAndExtensions(true);
  tinygltf::Model model;
  std::string err, warn;
  bool ok;
  try {
    ok = loader.LoadASCIIFromString(&model, &err, &warn, json.data(), unsigned(json.size()),
                                    baseDir);
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: {}", path, e.what()));
  }
  if (!ok || !err.empty()) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    throw InputError(fmt::format("{}: {}", path, err.empty() ? "not a valid glTF file" : err));
  }
  return model;
}

// ----------------------------------------------------------------- accessors

class Accessors {
 public:
  Accessors(const tinygltf::Model& model, std::string path)
      : model_(model), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(fmt::format("{}: {}", path_, message));
  }

  const tinygltf::Accessor& get(int index, const char* what) const {
    if (index < 0 || size_t(index) >= model_.accessors.size())
      fail(fmt::format("{}: accessor {} does not exist ({} accessors)", what, index,
                       model_.accessors.size()));
    return model_.accessors[size_t(index)];
  }

  // Reads accessor `index` as floats, `components` per element (checked).
  std::vector<float> floats(int index, int components, const char* what) const {
    const tinygltf::Accessor& a = get(index, what);
    int n = tinygltf::GetNumComponentsInType(uint32_t(a.type));
    if (n != components)
      fail(fmt::format("{}: accessor {} has {} components per element, {} expected", what, index, n,
                       components));
    check(a, index, what);
    std::vector<float> out(a.count * size_t(n), 0.0f);
    visit(a, index, what,
          [&](size_t i, int c, double v) { out[i * size_t(n) + size_t(c)] = float(v); });
    return out;
  }

  std::vector<uint32_t> indices(int index, const char* what) const {
    const tinygltf::Accessor& a = get(index, what);
    if (tinygltf::GetNumComponentsInType(uint32_t(a.type)) != 1)
      fail(fmt::format("{}: indices must be scalars", what));
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
        a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        a.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      fail(fmt::format("{}: indices must be unsigned integers", what));
    check(a, index, what);
    std::vector<uint32_t> out(a.count);
    visit(a, index, what, [&](size_t i, int, double v) { out[i] = uint32_t(v); });
    return out;
  }

  size_t count(int index, const char* what) const {
    const tinygltf::Accessor& a = get(index, what);
    check(a, index, what);
    return a.count;
  }

 private:
  // Before anything is allocated for it: does the accessor fit its buffer
  // view and the view its buffer?
  void check(const tinygltf::Accessor& a, int index, const char* what) const {
    visit(a, index, what, nullptr);
  }

  template <typename F>
  void visit(const tinygltf::Accessor& a, int index, const char* what, F&& f) const {
    if (a.sparse.isSparse)
      fail(fmt::format("{}: accessor {} is sparse (not supported)", what, index));
    if (a.count > size_t(INT32_MAX))
      fail(fmt::format("{}: accessor {} has {} elements: too many", what, index, a.count));
    const int n = tinygltf::GetNumComponentsInType(uint32_t(a.type));
    const int size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
    if (n <= 0 || size <= 0) fail(fmt::format("{}: accessor {} has an invalid type", what, index));
    if (a.bufferView < 0) return;  // all zeros
    if (size_t(a.bufferView) >= model_.bufferViews.size())
      fail(fmt::format("{}: accessor {} uses buffer view {} of {}", what, index, a.bufferView,
                       model_.bufferViews.size()));
    const tinygltf::BufferView& view = model_.bufferViews[size_t(a.bufferView)];
    if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
      fail(fmt::format("{}: buffer view {} uses buffer {} of {}", what, a.bufferView, view.buffer,
                       model_.buffers.size()));
    const std::vector<unsigned char>& data = model_.buffers[size_t(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      fail(fmt::format("{}: buffer view {} ({} bytes at {}) goes past its buffer ({} bytes)", what,
                       a.bufferView, view.byteLength, view.byteOffset, data.size()));
    const uint64_t element = uint64_t(n) * uint64_t(size);
    const uint64_t stride = view.byteStride ? view.byteStride : element;
    if (stride < element)
      fail(fmt::format("{}: buffer view {} stride {} is smaller than an element", what,
                       a.bufferView, stride));
    if (a.count > 0 &&
        (a.byteOffset > view.byteLength ||
         (uint64_t(a.count) - 1) * stride + element > view.byteLength - a.byteOffset))
      fail(fmt::format("{}: accessor {} ({} elements) goes past its buffer view ({} bytes)", what,
                       index, a.count, view.byteLength));
    if constexpr (std::is_same_v<std::decay_t<F>, std::nullptr_t>) {
      return;
    } else {
      const unsigned char* base = data.data() + view.byteOffset + a.byteOffset;
      for (size_t i = 0; i < a.count; ++i) {
        const unsigned char* e = base + i * stride;
        for (int c = 0; c < n; ++c)
          f(i, c, component(e + size_t(c) * size_t(size), a.componentType, a.normalized));
      }
    }
  }

  static double component(const unsigned char* p, int type, bool normalized) {
    switch (type) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        int8_t v;
        std::memcpy(&v, p, 1);
        return normalized ? std::max(v / 127.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? p[0] / 255.0 : p[0];
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      }
      case TINYGLTF_COMPONENT_TYPE_DOUBLE: {
        double v;
        std::memcpy(&v, p, 8);
        return v;
      }
    }
    return 0;
  }

  const tinygltf::Model& model_;
  std::string path_;
};

// ------------------------------------------------------------------- helpers

Affine3f fromTrs(const std::vector<double>& t, const std::vector<double>& r,
                 const std::vector<double>& s) {
  Affine3f m;
  if (r.size() == 4) {
    double x = r[0], y = r[1], z = r[2], w = r[3];
    double len = std::sqrt(x * x + y * y + z * z + w * w);
    if (len > 0) {
      x /= len, y /= len, z /= len, w /= len;
    } else {
      w = 1;
    }
    m.l[0][0] = float(1 - 2 * (y * y + z * z));
    m.l[0][1] = float(2 * (x * y - z * w));
    m.l[0][2] = float(2 * (x * z + y * w));
    m.l[1][0] = float(2 * (x * y + z * w));
    m.l[1][1] = float(1 - 2 * (x * x + z * z));
    m.l[1][2] = float(2 * (y * z - x * w));
    m.l[2][0] = float(2 * (x * z - y * w));
    m.l[2][1] = float(2 * (y * z + x * w));
    m.l[2][2] = float(1 - 2 * (x * x + y * y));
  }
  if (s.size() == 3)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m.l[i][j] *= float(s[size_t(j)]);
  if (t.size() == 3) m.t = {float(t[0]), float(t[1]), float(t[2])};
  return m;
}

Affine3f localTransform(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) {
    Affine3f m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m.l[r][c] = float(node.matrix[size_t(c * 4 + r)]);
      m.t[r] = float(node.matrix[size_t(12 + r)]);
    }
    return m;
  }
  return fromTrs(node.translation, node.rotation, node.scale);
}

bool isFiniteAffine(const Affine3f& a) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(a.l[r][c])) return false;
  return isFinite(a.t);
}

Vec3f colorOf(const std::vector<double>& v, Vec3f fallback) {
  if (v.size() < 3) return fallback;
  return {float(v[0]), float(v[1]), float(v[2])};
}

// Decodes an encoded image (PNG, JPEG, ...) from memory as 8-bit RGBA.
Texture decodeImage(const unsigned char* bytes, size_t size, const std::string& name) {
  if (size > size_t(INT32_MAX)) throw InputError(fmt::format("{}: image too large", name));
  int w = 0, h = 0, channels = 0;
  if (!stbi_info_from_memory(bytes, int(size), &w, &h, &channels))
    throw InputError(fmt::format("{}: cannot decode image: {}", name, stbi_failure_reason()));
  if (w <= 0 || h <= 0 || uint64_t(w) * uint64_t(h) > kMaxImagePixels)
    throw InputError(fmt::format("{}: image of {} x {} pixels is too large", name, w, h));
  unsigned char* pixels = stbi_load_from_memory(bytes, int(size), &w, &h, &channels, 4);
  if (!pixels)
    throw InputError(fmt::format("{}: cannot decode image: {}", name, stbi_failure_reason()));
  Texture t;
  t.name = name;
  t.width = w;
  t.height = h;
  t.rgba.assign(pixels, pixels + size_t(w) * size_t(h) * 4);
  stbi_image_free(pixels);
  return t;
}

// ------------------------------------------------------------------ building

class GltfBuilder {
 public:
  GltfBuilder(tinygltf::Model& model, std::string path, const LoadOptions& options)
      : model_(model),
        path_(std::move(path)),
        dir_(fs::path(path_).parent_path().empty() ? fs::path(".") : fs::path(path_).parent_path()),
        warnings_(options),
        accessors_(model, path_) {}

  Scene build() {
    scene_.name = fs::path(path_).stem().string();
    for (const std::string& ext : model_.extensionsUsed) {
      static const std::set<std::string> known = {"KHR_lights_punctual", "EXT_mesh_gpu_instancing",
                                                  "KHR_texture_transform"};
      if (!known.count(ext) && !kMaterialExtensions.count(ext))
        warnings_.once("ext|" + ext,
                       fmt::format("{}: extension {} is not supported and ignored", path_, ext));
    }
    for (const std::string& ext : model_.extensionsRequired)
      if (ext == "KHR_draco_mesh_compression" || ext == "EXT_meshopt_compression" ||
          ext == "KHR_mesh_quantization")
        throw InputError(fmt::format("{}: requires {}, which Ferry does not support", path_, ext));
    if (!model_.skins.empty() || !model_.animations.empty())
      warnings_.once("skins", fmt::format("{}: skins and animations are ignored (meshes are in "
                                          "their bind pose)",
                                          path_));
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      int s = model_.defaultScene >= 0 && size_t(model_.defaultScene) < model_.scenes.size()
                  ? model_.defaultScene
                  : 0;
      roots = model_.scenes[size_t(s)].nodes;
    } else {
      // No scene: every node that is nobody's child.
      std::vector<uint8_t> child(model_.nodes.size(), 0);
      for (const auto& n : model_.nodes)
        for (int c : n.children)
          if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = 1;
      for (size_t i = 0; i < model_.nodes.size(); ++i)
        if (!child[i]) roots.push_back(int(i));
    }
    std::vector<uint8_t> onPath(model_.nodes.size(), 0);
    for (int r : roots) visit(r, Affine3f::identity(), onPath, 0);
    if (scene_.instances.empty())
      throw InputError(fmt::format("{}: no triangles in the scene", path_));
    bool lights = !scene_.suns.empty() || !pendingLights_.empty();
    makeLights();
    if (scene_.views.empty()) {
      addDefaultView(scene_);
    }
    if (!lights) {
      SunLight sun;
      sun.direction = normalize(Vec3f(0.4f, 1.0f, 0.6f));
      scene_.suns.push_back(sun);
      scene_.environment.color = Vec3f(0.5f);
    }
    return std::move(scene_);
  }

 private:
  struct MaterialInfo {
    int32_t material = 0;
    // The texture coordinates (set, KHR_texture_transform) the meshes using
    // the material carry, and those the emissive texture is baked with.
    GltfTextureRef meshUvs, emissionUvs;
    std::shared_ptr<const Texture> emissionTexture;  // sRGB; only while loading
    Vec3f emissionFactor{0};
    std::map<std::tuple<int, int, int>, int32_t> emitting;  // quantised colour -> material
  };

  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(fmt::format("{}: {}", path_, message));
  }

  void visit(int index, const Affine3f& parent, std::vector<uint8_t>& onPath, int depth) {
    if (index < 0 || size_t(index) >= model_.nodes.size())
      fail(fmt::format("node {} does not exist ({} nodes)", index, model_.nodes.size()));
    if (onPath[size_t(index)] || depth > 1000)
      fail(fmt::format("node {} is its own ancestor", index));
    onPath[size_t(index)] = 1;
    const tinygltf::Node& node = model_.nodes[size_t(index)];
    Affine3f world = parent * localTransform(node);
    if (!isFiniteAffine(world)) fail(fmt::format("node {} has a non-finite transform", index));
    if (node.mesh >= 0) placeMesh(node, index, world);
    if (node.camera >= 0) addCamera(node.camera, world);
    auto light = node.extensions.find("KHR_lights_punctual");
    if (light != node.extensions.end() && light->second.IsObject() && light->second.Has("light")) {
      const tinygltf::Value& v = light->second.Get("light");
      if (!v.IsInt() && !v.IsNumber())
        fail(fmt::format("node {}: KHR_lights_punctual light is not an index", index));
      addLight(v.IsInt() ? v.Get<int>() : int(v.GetNumberAsDouble()), world);
    }
    for (int c : node.children) visit(c, world, onPath, depth + 1);
    onPath[size_t(index)] = 0;
  }

  void placeMesh(const tinygltf::Node& node, int nodeIndex, const Affine3f& world) {
    int32_t object = objectFor(node.mesh);
    if (object < 0) return;
    auto inst = node.extensions.find("EXT_mesh_gpu_instancing");
    if (inst == node.extensions.end() || !inst->second.IsObject() ||
        !inst->second.Has("attributes")) {
      addInstance(object, world, nodeIndex);
      return;
    }
    const tinygltf::Value& attrs = inst->second.Get("attributes");
    auto accessorOf = [&](const char* name) {
      if (!attrs.Has(name)) return -1;
      const tinygltf::Value& v = attrs.Get(name);
      return v.IsInt() ? v.Get<int>() : v.IsNumber() ? int(v.GetNumberAsDouble()) : -2;
    };
    int t = accessorOf("TRANSLATION"), r = accessorOf("ROTATION"), s = accessorOf("SCALE");
    if (t == -2 || r == -2 || s == -2)
      fail(fmt::format("node {}: EXT_mesh_gpu_instancing attribute is not an accessor index",
                       nodeIndex));
    size_t count = 0;
    bool any = false;
    for (int a : {t, r, s})
      if (a >= 0) {
        size_t c = accessors_.count(a, "EXT_mesh_gpu_instancing");
        if (any && c != count)
          fail(fmt::format("node {}: EXT_mesh_gpu_instancing attributes differ in count",
                           nodeIndex));
        count = c;
        any = true;
      }
    if (!any) {
      addInstance(object, world, nodeIndex);
      return;
    }
    std::vector<float> T =
        t >= 0 ? accessors_.floats(t, 3, "instance TRANSLATION") : std::vector<float>();
    std::vector<float> R =
        r >= 0 ? accessors_.floats(r, 4, "instance ROTATION") : std::vector<float>();
    std::vector<float> S =
        s >= 0 ? accessors_.floats(s, 3, "instance SCALE") : std::vector<float>();
    for (size_t i = 0; i < count; ++i) {
      std::vector<double> ti, ri, si;
      if (!T.empty()) ti = {T[3 * i], T[3 * i + 1], T[3 * i + 2]};
      if (!R.empty()) ri = {R[4 * i], R[4 * i + 1], R[4 * i + 2], R[4 * i + 3]};
      if (!S.empty()) si = {S[3 * i], S[3 * i + 1], S[3 * i + 2]};
      addInstance(object, world * fromTrs(ti, ri, si), nodeIndex);
    }
  }

  void addInstance(int32_t object, const Affine3f& transform, int nodeIndex) {
    float det = transform.determinant();
    if (!isFiniteAffine(transform))
      fail(fmt::format("node {}: non-finite instance transform", nodeIndex));
    if (det == 0) {
      warnings_.once("singular",
                     fmt::format("{}: node {} has a zero scale and is skipped", path_, nodeIndex));
      return;
    }
    scene_.instances.push_back({object, transform});
  }

  // ------------------------------------------------------------------ meshes

  int32_t objectFor(int meshIndex) {
    if (size_t(meshIndex) >= model_.meshes.size())
      fail(fmt::format("mesh {} does not exist ({} meshes)", meshIndex, model_.meshes.size()));
    auto it = objects_.find(meshIndex);
    if (it != objects_.end()) return it->second;
    const tinygltf::Mesh& gm = model_.meshes[size_t(meshIndex)];
    Object object;
    object.name = gm.name.empty() ? fmt::format("mesh{}", meshIndex) : gm.name;
    for (size_t p = 0; p < gm.primitives.size(); ++p) {
      std::string name = fmt::format("{}/{}", object.name, p);
      for (Mesh& m : primitiveMeshes(gm.primitives[p], name)) {
        scene_.meshes.push_back(std::move(m));
        object.meshes.push_back(int32_t(scene_.meshes.size() - 1));
      }
    }
    int32_t id = -1;
    if (!object.meshes.empty()) {
      scene_.objects.push_back(std::move(object));
      id = int32_t(scene_.objects.size() - 1);
    }
    objects_.emplace(meshIndex, id);
    return id;
  }

  std::vector<Mesh> primitiveMeshes(const tinygltf::Primitive& prim, const std::string& name) {
    const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      warnings_.once("mode",
                     fmt::format("{}: points and lines are not rendered (first: {})", path_, name));
      return {};
    }
    if (!prim.targets.empty())
      warnings_.once("morph",
                     fmt::format("{}: morph targets are ignored (first: {})", path_, name));
    auto attr = [&](const char* key) {
      auto it = prim.attributes.find(key);
      return it == prim.attributes.end() ? -1 : it->second;
    };
    int position = attr("POSITION");
    if (position < 0) fail(fmt::format("{}: primitive without POSITION", name));
    Mesh mesh;
    mesh.name = name;
    {
      std::vector<float> p = accessors_.floats(position, 3, "POSITION");
      mesh.positions.reserve(p.size() / 3 + 1);  // Mesh::hasVertexSlack
      mesh.positions.resize(p.size() / 3);
      if (!p.empty())  // memcpy from an empty vector's null data() is undefined
        std::memcpy(static_cast<void*>(mesh.positions.data()), p.data(), p.size() * sizeof(float));
    }
    const size_t n = mesh.positions.size();
    for (size_t i = 0; i < n; ++i)
      if (!isFinite(mesh.positions[i])) fail(fmt::format("{}: position {} is not finite", name, i));
    if (int normal = attr("NORMAL"); normal >= 0) {
      std::vector<float> v = accessors_.floats(normal, 3, "NORMAL");
      if (v.size() / 3 != n)
        fail(fmt::format("{}: {} normals for {} positions", name, v.size() / 3, n));
      mesh.normals.resize(n);
      std::memcpy(static_cast<void*>(mesh.normals.data()), v.data(), v.size() * sizeof(float));
      for (size_t i = 0; i < n; ++i)
        if (!isFinite(mesh.normals[i])) fail(fmt::format("{}: normal {} is not finite", name, i));
    }
    if (prim.material >= 0 && size_t(prim.material) >= model_.materials.size())
      fail(fmt::format("{}: material {} does not exist ({} materials)", name, prim.material,
                       model_.materials.size()));
    // The material first: its textures say which uvs the mesh carries.
    MaterialInfo& info = materialFor(prim.material);
    mesh.material = info.material;
    mesh.uvs = textureCoordinates(prim, info.meshUvs, n, name);
    std::vector<uint32_t> idx;
    if (prim.indices >= 0) {
      idx = accessors_.indices(prim.indices, "indices");
    } else {
      idx.resize(n);
      for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
    }
    for (size_t i = 0; i < idx.size(); ++i)
      if (idx[i] >= n)
        fail(fmt::format("{}: index {} (entry {}) is out of range: {} vertices", name, idx[i], i,
                         n));
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      if (idx.size() % 3 != 0)
        fail(fmt::format("{}: {} indices is not a multiple of 3", name, idx.size()));
      for (size_t i = 0; i + 2 < idx.size(); i += 3)
        mesh.indices.push_back({int32_t(idx[i]), int32_t(idx[i + 1]), int32_t(idx[i + 2])});
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      for (size_t i = 0; i + 2 < idx.size(); ++i)
        mesh.indices.push_back(
            i % 2 == 0 ? Vec3i{int32_t(idx[i]), int32_t(idx[i + 1]), int32_t(idx[i + 2])}
                       : Vec3i{int32_t(idx[i + 1]), int32_t(idx[i]), int32_t(idx[i + 2])});
    } else {
      for (size_t i = 1; i + 1 < idx.size(); ++i)
        mesh.indices.push_back({int32_t(idx[0]), int32_t(idx[i]), int32_t(idx[i + 1])});
    }
    if (mesh.indices.empty()) return {};
    for (Vec3f& nn : mesh.normals) {
      float len = length(nn);
      nn = len > 0 ? nn / len : Vec3f(0, 0, 1);
    }
    if (!info.emissionTexture) return splitByEmission(std::move(mesh), info, {});
    std::vector<Vec2f> ownUvs;  // when the emissive texture reads other uvs than the mesh keeps
    if (!info.emissionUvs.sameUvsAs(info.meshUvs))
      ownUvs = textureCoordinates(prim, info.emissionUvs, n, name);
    const std::span<const Vec2f> emissionUvs =
        info.emissionUvs.sameUvsAs(info.meshUvs) ? mesh.uvs.span() : std::span<const Vec2f>(ownUvs);
    if (emissionUvs.empty()) {
      warnings_.once("emission uv", fmt::format("{}: {} has an emissive texture but no texture "
                                                "coordinates: uses the factor alone",
                                                path_, name));
      return splitByEmission(std::move(mesh), info, {});
    }
    std::vector<Vec3f> emission = emissionPerTriangle(mesh, emissionUvs, info);
    return splitByEmission(std::move(mesh), info, emission);
  }

  // The primitive's TEXCOORD_<set> as `ref` reads it: its
  // KHR_texture_transform applied (in glTF's uv space), then v flipped to
  // Ferry's (v up the image). Empty when the primitive has no such set.
  std::vector<Vec2f> textureCoordinates(const tinygltf::Primitive& prim, const GltfTextureRef& ref,
                                        size_t vertices, const std::string& name) {
    auto it = prim.attributes.find(fmt::format("TEXCOORD_{}", ref.texCoord));
    if (it == prim.attributes.end()) return {};
    std::vector<float> v = accessors_.floats(it->second, 2, "TEXCOORD");
    if (v.size() / 2 != vertices)
      fail(
          fmt::format("{}: {} texture coordinates for {} positions", name, v.size() / 2, vertices));
    std::vector<Vec2f> uvs(vertices);
    for (size_t i = 0; i < vertices; ++i) {
      if (!std::isfinite(v[2 * i]) || !std::isfinite(v[2 * i + 1]))
        fail(fmt::format("{}: texture coordinate {} is not finite", name, i));
      const Vec2f uv = ref.transform.apply({v[2 * i], v[2 * i + 1]});
      uvs[i] = {uv.x, 1 - uv.y};
    }
    return uvs;
  }

  // ---------------------------------------------------------------- emission

  std::vector<Vec3f> emissionPerTriangle(const Mesh& mesh, std::span<const Vec2f> uvs,
                                         const MaterialInfo& info) {
    const Texture& t = *info.emissionTexture;
    std::vector<Vec3f> e(mesh.indices.size());
    static constexpr float kPoints[4][3] = {{1.f / 3, 1.f / 3, 1.f / 3},
                                            {2.f / 3, 1.f / 6, 1.f / 6},
                                            {1.f / 6, 2.f / 3, 1.f / 6},
                                            {1.f / 6, 1.f / 6, 2.f / 3}};
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
      const Vec3i& tri = mesh.indices[i];
      Vec3f sum(0);
      for (const auto& w : kPoints) {
        Vec2f uv =
            uvs[size_t(tri.x)] * w[0] + uvs[size_t(tri.y)] * w[1] + uvs[size_t(tri.z)] * w[2];
        sum += t.sample(uv).xyz();
      }
      e[i] = sum * 0.25f * info.emissionFactor;
    }
    return e;
  }

  // Splits triangles by quantised emission; `emission` empty: one mesh.
  std::vector<Mesh> splitByEmission(Mesh mesh, MaterialInfo& info,
                                    const std::vector<Vec3f>& emission) {
    std::vector<Mesh> out;
    if (emission.empty()) {
      out.push_back(std::move(mesh));
      return out;
    }
    float maxE = 0;
    for (const Vec3f& e : emission) maxE = std::max(maxE, maxComponent(e));
    if (!(maxE > 0)) {
      out.push_back(std::move(mesh));
      return out;
    }
    std::map<std::tuple<int, int, int>, std::vector<size_t>> groups;
    std::map<std::tuple<int, int, int>, Vec3f> sums;
    for (size_t i = 0; i < emission.size(); ++i) {
      Vec3f q = emission[i] / maxE * float(kEmissionLevels);
      auto key =
          std::make_tuple(int(std::lround(q.x)), int(std::lround(q.y)), int(std::lround(q.z)));
      groups[key].push_back(i);
      sums[key] += emission[i];
    }
    for (auto& [key, tris] : groups) {
      Mesh sub;
      sub.name = mesh.name;
      std::vector<int32_t> remap(mesh.positions.size(), -1);
      for (size_t t : tris) {
        Vec3i tri = mesh.indices[t];
        for (int k = 0; k < 3; ++k) {
          int32_t& r = remap[size_t(tri[k])];
          if (r < 0) {
            r = int32_t(sub.positions.size());
            sub.positions.push_back(mesh.positions[size_t(tri[k])]);
            if (!mesh.normals.empty()) sub.normals.push_back(mesh.normals[size_t(tri[k])]);
            if (!mesh.uvs.empty()) sub.uvs.push_back(mesh.uvs[size_t(tri[k])]);
          }
        }
        sub.indices.push_back({remap[size_t(tri.x)], remap[size_t(tri.y)], remap[size_t(tri.z)]});
      }
      if (key == std::make_tuple(0, 0, 0)) {
        sub.material = info.material;
      } else {
        auto it = info.emitting.find(key);
        if (it == info.emitting.end()) {
          Material m = scene_.materials[size_t(info.material)];
          m.emission = sums[key] / float(tris.size());
          m.name += fmt::format(" (emission {:.3g} {:.3g} {:.3g})", m.emission.x, m.emission.y,
                                m.emission.z);
          it = info.emitting.emplace(key, scene_.addMaterial(m)).first;
        }
        sub.material = it->second;
        sub.name += " (emitting)";
      }
      out.push_back(std::move(sub));
    }
    return out;
  }

  // --------------------------------------------------------------- materials

  WrapMode wrapOf(int textureIndex) {
    const tinygltf::Texture& t = model_.textures[size_t(textureIndex)];
    if (t.sampler < 0 || size_t(t.sampler) >= model_.samplers.size()) return WrapMode::Repeat;
    int wrap = model_.samplers[size_t(t.sampler)].wrapS;
    if (wrap == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE) return WrapMode::Clamp;
    if (wrap == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT) return WrapMode::Mirror;
    return WrapMode::Repeat;
  }

  // Texture `index` as a scene texture (cached), or kNoTexture with a warning.
  // `srgb` false: the texels are data (a normal map) and stay as they are.
  int32_t textureFor(int index, const std::string& use, bool srgb) {
    if (index < 0) return kNoTexture;
    auto key = std::make_pair(index, srgb);
    auto it = textures_.find(key);
    if (it != textures_.end()) return it->second;
    std::shared_ptr<Texture> texture = decodeTexture(index, use);
    int32_t id = kNoTexture;
    if (texture) {
      texture->srgb = srgb;
      scene_.textures.push_back(std::move(*texture));
      id = int32_t(scene_.textures.size() - 1);
    }
    textures_.emplace(key, id);
    return id;
  }

  // Texture `index` decoded for use while loading only (averaged, baked):
  // cached for this load, never part of the scene. Null with a warning.
  std::shared_ptr<const Texture> temporaryTexture(int index, const std::string& use) {
    auto it = temporary_.find(index);
    if (it != temporary_.end()) return it->second;
    std::shared_ptr<const Texture> texture = decodeTexture(index, use);
    temporary_.emplace(index, texture);
    return texture;
  }

  // The mean of a texture that scales a parameter Ferry does not texture
  // (metallic, roughness, transmission, the specular and clear-coat
  // factors): RGBA in [0, 1], the colour channels decoded from sRGB when
  // `srgb`. Over the whole image: a KHR_texture_transform does not change
  // it. Without a texture, or one that cannot be read (warned): all 1.
  Vec4f meanOf(const GltfTextureRef& ref, const std::string& use, bool srgb,
               const std::string& material) {
    if (!ref.present()) return Vec4f{1, 1, 1, 1};
    std::shared_ptr<const Texture> texture = temporaryTexture(ref.index, use);
    if (!texture || texture->texelCount() == 0) return Vec4f{1, 1, 1, 1};
    warnings_.once("averaged|" + use,
                   fmt::format("{}: {} textures are averaged (Ferry does not texture the "
                               "parameter they scale; first: material \"{}\")",
                               path_, use, material));
    std::array<double, 256> decode;
    for (int i = 0; i < 256; ++i) decode[size_t(i)] = srgb ? srgbToLinear(i / 255.0f) : i / 255.0;
    double sum[4] = {0, 0, 0, 0};
    const size_t texels = texture->texelCount();
    for (size_t i = 0; i < texels; ++i)
      for (int c = 0; c < 4; ++c) {
        const uint8_t v = texture->rgba[4 * i + size_t(c)];
        sum[c] += c < 3 ? decode[v] : v / 255.0;
      }
    return {float(sum[0] / double(texels)), float(sum[1] / double(texels)),
            float(sum[2] / double(texels)), float(sum[3] / double(texels))};
  }

  std::shared_ptr<Texture> decodeTexture(int index, const std::string& use) {
    if (size_t(index) >= model_.textures.size())
      fail(fmt::format("{} texture {} does not exist ({} textures)", use, index,
                       model_.textures.size()));
    const tinygltf::Texture& t = model_.textures[size_t(index)];
    if (!t.extensions.empty())
      for (const auto& [ext, v] : t.extensions)
        warnings_.once("texext|" + ext,
                       fmt::format("{}: texture extension {} ignored", path_, ext));
    if (t.source < 0) {
      warnings_.once("nosource",
                     fmt::format("{}: texture {} has no image Ferry can read", path_, index));
      return nullptr;
    }
    if (size_t(t.source) >= model_.images.size())
      fail(fmt::format("texture {} uses image {} of {}", index, t.source, model_.images.size()));
    tinygltf::Image& image = model_.images[size_t(t.source)];
    std::string label = image.name.empty() ? fmt::format("image {}", t.source)
                                           : fmt::format("image {} ({})", t.source, image.name);
    Texture texture;
    if (image.bufferView >= 0) {
      if (size_t(image.bufferView) >= model_.bufferViews.size())
        fail(fmt::format("{} uses buffer view {} of {}", label, image.bufferView,
                         model_.bufferViews.size()));
      const tinygltf::BufferView& view = model_.bufferViews[size_t(image.bufferView)];
      if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
        fail(fmt::format("{}: buffer view {} uses buffer {} of {}", label, image.bufferView,
                         view.buffer, model_.buffers.size()));
      const auto& data = model_.buffers[size_t(view.buffer)].data;
      if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
        fail(fmt::format("{}: buffer view {} goes past its buffer", label, image.bufferView));
      texture = decodeImage(data.data() + view.byteOffset, view.byteLength,
                            fmt::format("{}: {}", path_, label));
    } else if (!image.image.empty()) {
      texture =
          decodeImage(image.image.data(), image.image.size(), fmt::format("{}: {}", path_, label));
      std::vector<unsigned char>().swap(image.image);
    } else {
      fs::path file = dir_ / urlDecode(image.uri);
      std::error_code ec;
      if (image.uri.empty() || !fs::is_regular_file(file, ec))
        fail(fmt::format("{}: file \"{}\" not found (looked for {})", label, image.uri,
                         file.string()));
      texture = readTexture(file.string());
    }
    texture.wrap = wrapOf(index);
    return std::make_shared<Texture>(std::move(texture));
  }

  // A core textureInfo (baseColorTexture, normalTexture, ...), checked, with
  // its KHR_texture_transform; its other extensions are ignored (warned).
  template <typename Info>
  GltfTextureRef coreTexture(const GltfMaterialValues& values, const Info& info, const char* what,
                             const std::string& material) {
    for (const auto& [ext, v] : info.extensions)
      if (ext != "KHR_texture_transform")
        warnings_.once("texinfo|" + ext,
                       fmt::format("{}: texture extension {} ignored (first: material \"{}\")",
                                   path_, ext, material));
    return values.texture(info.index, info.texCoord, info.extensions_json_string, what);
  }

  // The uvs the mesh carries serve the textures looked up while rendering:
  // the base colour's (and its alpha's), or the normal map's when there is
  // no base colour texture. A normal map on other uvs uses them anyway.
  GltfTextureRef meshUvsFor(const GltfTextureRef& baseColor, const GltfTextureRef& normal,
                            const std::string& material) {
    if (!baseColor.present()) return normal.present() ? normal : GltfTextureRef{};
    if (normal.present() && !normal.sameUvsAs(baseColor))
      warnings_.once(
          "normal uvs",
          fmt::format("{}: material \"{}\": normalTexture and baseColorTexture use "
                      "other texture coordinates (set or KHR_texture_transform); Ferry's "
                      "meshes have one: the normal map is looked up with the base "
                      "colour's",
                      path_, material));
    return baseColor;
  }

  MaterialInfo& materialFor(int index) {
    auto it = materials_.find(index);
    if (it != materials_.end()) return it->second;
    MaterialInfo info;
    Material m;
    if (index < 0) {
      // glTF's default material: white, metallic 1, roughness 1. A white
      // rough metal is a poor grey; use a grey diffuse, as viewers do.
      m.name = "default";
      m.baseColor = Vec3f(0.8f);
      info.material = scene_.addMaterial(m);
      return materials_.emplace(index, info).first->second;
    }
    const tinygltf::Material& g = model_.materials[size_t(index)];
    m.name = g.name.empty() ? fmt::format("material{}", index) : g.name;
    const GltfMaterialValues values(fmt::format("{}: material \"{}\"", path_, m.name),
                                    model_.textures.size());
    const nlohmann::json extensions = values.parseExtensions(g.extensions_json_string, "material");
    for (const auto& [ext, v] : extensions.items())
      if (!kMaterialExtensions.count(ext))
        warnings_.once("matext|" + ext,
                       fmt::format("{}: material extension {} ignored", path_, ext));

    const auto& pbr = g.pbrMetallicRoughness;
    const GltfTextureRef baseColorRef =
        coreTexture(values, pbr.baseColorTexture, "baseColorTexture", m.name);
    const GltfTextureRef metallicRoughnessRef =
        coreTexture(values, pbr.metallicRoughnessTexture, "metallicRoughnessTexture", m.name);
    const GltfTextureRef normalRef = coreTexture(values, g.normalTexture, "normalTexture", m.name);
    const GltfTextureRef emissiveRef =
        coreTexture(values, g.emissiveTexture, "emissiveTexture", m.name);
    coreTexture(values, g.occlusionTexture, "occlusionTexture", m.name);

    Vec3f base = colorOf(pbr.baseColorFactor, Vec3f(1));
    float alphaFactor = pbr.baseColorFactor.size() == 4 ? float(pbr.baseColorFactor[3]) : 1.0f;
    m.baseColor = min(max(base, Vec3f(0)), Vec3f(1));
    m.baseColorTexture = textureFor(baseColorRef.index, "baseColor", true);
    MetallicRoughness surface;
    surface.metallic = std::clamp(float(pbr.metallicFactor), 0.0f, 1.0f);
    surface.roughness = std::clamp(float(pbr.roughnessFactor), 0.0f, 1.0f);
    const Vec4f metallicRoughness =
        meanOf(metallicRoughnessRef, "metallicRoughness", false, m.name);
    surface.roughness *= metallicRoughness.y;
    surface.metallic *= metallicRoughness.z;

    readTransmission(values, extensions, m.name, surface);
    const float ior = readIor(values, extensions, surface);
    readSpecularLayers(values, extensions, ior, m.name, surface);
    m.model = modelOf(surface);
    readNormalMap(values, g.normalTexture, normalRef, m);
    if (g.occlusionTexture.index >= 0)
      warnings_.once("occlusion", fmt::format("{}: occlusion textures are ignored (a path tracer "
                                              "traces the occlusion they approximate)",
                                              path_));

    // Emission. glTF culls the back faces of single-sided materials, so an
    // emitter is seen, and lights, only from its front (the side its
    // counter-clockwise winding faces), unless it is double-sided.
    m.emitsBackSide = g.doubleSided;
    float strength = 1;
    if (const nlohmann::json* e = values.extension(extensions, "KHR_materials_emissive_strength"))
      strength = values.number(*e, "KHR_materials_emissive_strength", "emissiveStrength", 1, 0);
    Vec3f emissive = max(colorOf(g.emissiveFactor, Vec3f(0)), Vec3f(0)) * strength;
    if (emissiveRef.present() && maxComponent(emissive) > 0) {
      info.emissionTexture = temporaryTexture(emissiveRef.index, "emissive");
      info.emissionFactor = emissive;
      info.emissionUvs = emissiveRef;
      if (!info.emissionTexture) m.emission = emissive;
    } else {
      m.emission = emissive;
    }

    if (g.alphaMode == "MASK" || g.alphaMode == "BLEND") {
      m.alphaCutoff = g.alphaMode == "MASK" ? float(g.alphaCutoff) : 0.5f;
      if (g.alphaMode == "BLEND")
        warnings_.once("blend",
                       fmt::format("{}: alphaMode BLEND is rendered as a cut-out at 0.5", path_));
      if (m.baseColorTexture != kNoTexture) {
        if (alphaFactor == 1) {
          m.alphaTexture = m.baseColorTexture;
        } else {
          Texture scaled = scene_.textures[size_t(m.baseColorTexture)];
          for (size_t i = 3; i < scaled.rgba.size(); i += 4)
            scaled.rgba[i] =
                uint8_t(std::lround(std::clamp(scaled.rgba[i] * alphaFactor, 0.0f, 255.0f)));
          scene_.textures.push_back(std::move(scaled));
          m.alphaTexture = int32_t(scene_.textures.size() - 1);
        }
      } else if (alphaFactor < m.alphaCutoff) {
        Texture hole;
        hole.name = "transparent";
        hole.width = hole.height = 1;
        hole.srgb = false;
        hole.rgba = {255, 255, 255, 0};
        scene_.textures.push_back(std::move(hole));
        m.alphaTexture = int32_t(scene_.textures.size() - 1);
      }
    }
    info.meshUvs = meshUvsFor(baseColorRef, normalRef, m.name);
    info.material = scene_.addMaterial(m);
    return materials_.emplace(index, info).first->second;
  }

  // KHR_materials_transmission: the factor times the mean of the texture's
  // red channel. Ferry's dielectric takes over at 0.5
  // (material/metallic_roughness.h).
  void readTransmission(const GltfMaterialValues& values, const nlohmann::json& extensions,
                        const std::string& material, MetallicRoughness& surface) {
    const char* what = "KHR_materials_transmission";
    const nlohmann::json* e = values.extension(extensions, what);
    if (!e) return;
    surface.transmission = values.number(*e, what, "transmissionFactor", 0, 0, 1);
    surface.transmission *=
        meanOf(values.texture(*e, what, "transmissionTexture"), "transmission", false, material).x;
  }

  // KHR_materials_ior: 0 or at least 1. The ior refracts (transmission) and
  // sets the specular layer's Fresnel term. 0 is the spec's legacy value
  // (F0 = 1, the specular colour is the reflectance): it has no refraction,
  // so a transmitting material keeps 1.5.
  float readIor(const GltfMaterialValues& values, const nlohmann::json& extensions,
                MetallicRoughness& surface) {
    const char* what = "KHR_materials_ior";
    const nlohmann::json* e = values.extension(extensions, what);
    if (!e) return 1.5f;
    const float ior = values.number(*e, what, "ior", 1.5f);
    if (!(ior == 0 || ior >= 1))
      values.fail(fmt::format("{} ior is {}: must be 0 or at least 1", what, ior));
    if (ior >= 1) surface.ior = ior;
    return ior;
  }

  // The dielectric specular layer glTF puts over every non-metallic base
  // (KHR_materials_ior, KHR_materials_specular) and KHR_materials_clearcoat,
  // as Ferry's layered coat (io/gltf/gltf_specular_layers.h says how). Metals
  // stay bare conductors: a clear coat on one is dropped.
  void readSpecularLayers(const GltfMaterialValues& values, const nlohmann::json& extensions,
                          float ior, const std::string& material, MetallicRoughness& surface) {
    GltfSpecularLayers layers;
    layers.ior = ior;
    layers.roughness = surface.roughness;
    if (const nlohmann::json* e = values.extension(extensions, "KHR_materials_specular")) {
      const char* what = "KHR_materials_specular";
      layers.specularFactor = values.number(*e, what, "specularFactor", 1, 0, 1);
      layers.specularFactor *=
          meanOf(values.texture(*e, what, "specularTexture"), "specular", false, material).w;
      // The colour may exceed 1: F0 = min(F0(ior) * colour, 1).
      const Vec3f color = values.color(*e, what, "specularColorFactor", Vec3f(1), 0,
                                       std::numeric_limits<float>::max());
      layers.specularColor = color * meanOf(values.texture(*e, what, "specularColorTexture"),
                                            "specularColor", true, material)
                                         .xyz();
    }
    if (const nlohmann::json* e = values.extension(extensions, "KHR_materials_clearcoat")) {
      const char* what = "KHR_materials_clearcoat";
      layers.clearcoat = values.number(*e, what, "clearcoatFactor", 0, 0, 1);
      layers.clearcoat *=
          meanOf(values.texture(*e, what, "clearcoatTexture"), "clearcoat", false, material).x;
      layers.clearcoatRoughness = values.number(*e, what, "clearcoatRoughnessFactor", 0, 0, 1);
      layers.clearcoatRoughness *= meanOf(values.texture(*e, what, "clearcoatRoughnessTexture"),
                                          "clearcoatRoughness", false, material)
                                       .y;
      if (values.texture(*e, what, "clearcoatNormalTexture").present())
        warnings_.once("clearcoat normal",
                       fmt::format("{}: clearcoatNormalTexture is ignored (Ferry's coat uses the "
                                   "material's normal; first: material \"{}\")",
                                   path_, material));
    }
    if (surface.metallic >= 0.5f) {
      if (layers.clearcoat > 0)
        warnings_.once("clearcoat metal",
                       fmt::format("{}: a clear coat on a metallic material is dropped (Ferry's "
                                   "conductor has no coat; first: material \"{}\")",
                                   path_, material));
      return;
    }
    if (layers.clearcoat > 0)
      warnings_.once("clearcoat",
                     fmt::format("{}: KHR_materials_clearcoat: Ferry has one coat, the clear coat "
                                 "and the specular layer under it mixed by clearcoatFactor "
                                 "(first: material \"{}\")",
                                 path_, material));
    const FerryCoat coat = ferryCoatOf(layers);
    surface.coat = coat.tint;
    surface.coatRoughness = coat.roughness;
    surface.coatEta = coat.eta;
    surface.coatLayered = true;
  }

  // normalTexture: a tangent-space normal map, its texels kept as they are
  // (linear data, not sRGB colour).
  void readNormalMap(const GltfMaterialValues& values, const tinygltf::NormalTextureInfo& info,
                     const GltfTextureRef& ref, Material& m) {
    if (!ref.present()) return;
    if (!std::isfinite(float(info.scale)))
      values.fail(fmt::format("normalTexture scale is {}: not a finite single-precision number",
                              info.scale));
    m.normalTexture = textureFor(ref.index, "normal", false);
    m.normalScale = float(info.scale);
  }

  // ------------------------------------------------------- cameras and lights

  void addCamera(int index, const Affine3f& world) {
    if (size_t(index) >= model_.cameras.size())
      fail(fmt::format("camera {} does not exist ({} cameras)", index, model_.cameras.size()));
    const tinygltf::Camera& c = model_.cameras[size_t(index)];
    CameraView view;
    std::string base = c.name.empty() ? fmt::format("camera{}", index) : c.name;
    int uses = ++cameraUses_[base];
    view.name = uses == 1 ? base : fmt::format("{}#{}", base, uses);
    view.from = world.transformPoint(Vec3f(0));
    Vec3f forward = world.transformVector({0, 0, -1});
    Vec3f up = world.transformVector({0, 1, 0});
    if (!(length(forward) > 0) || !(length(up) > 0))
      fail(fmt::format("camera {} has a degenerate transform", index));
    view.at = view.from + normalize(forward);
    view.up = normalize(up);
    if (c.type == "perspective" && c.perspective.yfov > 0 && c.perspective.yfov < kPi) {
      view.fovY = float(c.perspective.yfov * 180 / kPi);
    } else {
      view.fovY = 45;
      warnings_.once("camtype|" + c.type,
                     fmt::format("{}: {} camera \"{}\" rendered as a perspective camera "
                                 "with fov 45",
                                 path_, c.type, view.name));
    }
    scene_.views.push_back(view);
  }

  struct PendingLight {
    Vec3f position, direction, intensity;
    float coneDegrees;
    std::string name;
  };

  void addLight(int index, const Affine3f& world) {
    if (index < 0 || size_t(index) >= model_.lights.size())
      fail(fmt::format("light {} does not exist ({} lights)", index, model_.lights.size()));
    const tinygltf::Light& l = model_.lights[size_t(index)];
    Vec3f color = max(colorOf(l.color, Vec3f(1)), Vec3f(0)) * float(std::max(l.intensity, 0.0));
    Vec3f dir = world.transformVector({0, 0, -1});
    std::string name = l.name.empty() ? fmt::format("light{}", index) : l.name;
    if (l.type == "directional") {
      if (!(length(dir) > 0)) fail(fmt::format("light {} has a degenerate transform", index));
      SunLight sun;
      sun.direction = normalize(-dir);
      sun.irradiance = color;
      scene_.suns.push_back(sun);
    } else if (l.type == "point" || l.type == "spot") {
      PendingLight p{world.transformPoint(Vec3f(0)),
                     length(dir) > 0 ? normalize(dir) : Vec3f(0, 0, -1), color, 180, name};
      if (l.type == "spot")
        p.coneDegrees = float(std::clamp(l.spot.outerConeAngle, 0.01, double(kPi) / 2) * 180 / kPi);
      pendingLights_.push_back(p);
    } else {
      warnings_.once("lighttype|" + l.type,
                     fmt::format("{}: light type \"{}\" ignored", path_, l.type));
    }
  }

  void makeLights() {
    if (pendingLights_.empty()) return;
    Box3f bounds = scene_.worldBounds();
    for (const PendingLight& p : pendingLights_) bounds.extend(p.position);
    float radius = pointLightRadius(bounds);
    for (const PendingLight& p : pendingLights_) {
      if (p.coneDegrees >= 180)
        addPointLightEmitter(scene_, p.position, p.intensity, radius, p.name);
      else
        addSpotLightEmitter(scene_, p.position, p.direction, p.intensity, p.coneDegrees, radius,
                            p.name);
    }
  }

  tinygltf::Model& model_;
  std::string path_;
  fs::path dir_;
  LoadWarnings warnings_;
  Accessors accessors_;
  Scene scene_;
  std::map<int, int32_t> objects_;
  std::map<std::pair<int, bool>, int32_t> textures_;
  std::map<int, std::shared_ptr<const Texture>> temporary_;
  std::map<int, MaterialInfo> materials_;
  std::map<std::string, int> cameraUses_;
  std::vector<PendingLight> pendingLights_;
};

}  // namespace

Scene loadGltf(const std::string& path, const LoadOptions& options) {
  tinygltf::Model model = parseModel(path, options);
  GltfBuilder builder(model, path, options);
  return builder.build();
}

}  // namespace ferry
