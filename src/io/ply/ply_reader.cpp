#include "io/ply/ply_reader.h"

#include <bit>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include "core/error.h"
#include "io/default_lighting.h"
#include "shapes/spheres.h"

namespace ferry {
namespace {

constexpr size_t kMaxHeaderLine = 4096;
constexpr uint64_t kMaxHeaderBytes = uint64_t(1) << 20;
constexpr uint64_t kMaxElements = INT32_MAX;  // 32-bit indices
constexpr int64_t kMaxPolygon = 1 << 16;      // vertices in one face

enum class Format { Ascii, BinaryLittle, BinaryBig };

enum class Type : uint8_t { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

int sizeOf(Type t) {
  switch (t) {
    case Type::Int8:
    case Type::Uint8:
      return 1;
    case Type::Int16:
    case Type::Uint16:
      return 2;
    case Type::Int32:
    case Type::Uint32:
    case Type::Float32:
      return 4;
    case Type::Float64:
      return 8;
  }
  return 1;
}

bool isInteger(Type t) {
  return t != Type::Float32 && t != Type::Float64;
}

std::optional<Type> parseType(std::string_view s) {
  if (s == "char" || s == "int8") return Type::Int8;
  if (s == "uchar" || s == "uint8") return Type::Uint8;
  if (s == "short" || s == "int16") return Type::Int16;
  if (s == "ushort" || s == "uint16") return Type::Uint16;
  if (s == "int" || s == "int32") return Type::Int32;
  if (s == "uint" || s == "uint32") return Type::Uint32;
  if (s == "float" || s == "float32") return Type::Float32;
  if (s == "double" || s == "float64") return Type::Float64;
  return std::nullopt;
}

struct Property {
  std::string name;
  Type type = Type::Float32;  // the item type for lists
  bool isList = false;
  Type countType = Type::Uint8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  int line = 0;  // of its `element` line, for messages
};

struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  int lines = 0;  // header lines, so ASCII body lines continue the count
};

void splitWords(std::string_view line, std::vector<std::string_view>& words) {
  words.clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) words.push_back(line.substr(b, i - b));
  }
}

bool parseCount(std::string_view s, uint64_t& out) {
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return !s.empty() && ec == std::errc() && end == s.data() + s.size();
}

Header readHeader(ByteStream& in) {
  Header h;
  std::string line;
  std::vector<std::string_view> words;
  bool sawFormat = false, sawEnd = false;
  auto where = [&]() { return SourceLocation{in.name(), h.lines}; };
  auto fail = [&](const std::string& message) { throw InputError(where(), message); };
  while (!sawEnd) {
    line.clear();
    bool terminated = false;
    for (int c; (c = in.get()) >= 0;) {
      if (c == '\n') {
        terminated = true;
        break;
      }
      if (line.size() >= kMaxHeaderLine) {
        ++h.lines;
        fail(h.lines == 1 ? "not a PLY file (no 'ply' line)"
                          : "header line longer than 4096 bytes (not a PLY file?)");
      }
      line.push_back(char(c));
    }
    ++h.lines;
    if (!terminated && line.empty()) {
      if (h.lines == 1) fail("empty file: not a PLY file");
      fail("file ends inside the header (no end_header): truncated?");
    }
    if (in.offset() > kMaxHeaderBytes) fail("header longer than 1 MiB (not a PLY file?)");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (h.lines == 1) {
      if (line != "ply") fail("not a PLY file (the first line must be 'ply')");
      continue;
    }
    if (line.find('\0') != std::string::npos) fail("NUL byte in the header: not a PLY header");
    if (!terminated) fail("file ends inside the header (no end_header): truncated?");
    splitWords(line, words);
    if (words.empty()) continue;
    std::string_view key = words[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      if (words.size() != 3) fail("format line needs a format and a version");
      if (words[1] == "ascii")
        h.format = Format::Ascii;
      else if (words[1] == "binary_little_endian")
        h.format = Format::BinaryLittle;
      else if (words[1] == "binary_big_endian")
        h.format = Format::BinaryBig;
      else
        fail(fmt::format("unknown format '{}' (ascii, binary_little_endian, binary_big_endian)",
                         words[1]));
      if (!words[2].starts_with("1.")) fail(fmt::format("unsupported PLY version '{}'", words[2]));
      sawFormat = true;
    } else if (key == "element") {
      if (words.size() != 3) fail("element line needs a name and a count");
      Element e;
      e.name = std::string(words[1]);
      if (!parseCount(words[2], e.count))
        fail(fmt::format("element '{}': count '{}' is not a non-negative integer", words[1],
                         words[2]));
      e.line = h.lines;
      for (const Element& other : h.elements)
        if (other.name == e.name) fail(fmt::format("element '{}' defined twice", e.name));
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) fail("property before any element");
      Property p;
      if (words.size() >= 2 && words[1] == "list") {
        if (words.size() != 5) fail("list property needs: property list COUNT_TYPE ITEM_TYPE NAME");
        auto countType = parseType(words[2]);
        auto itemType = parseType(words[3]);
        if (!countType) fail(fmt::format("unknown type '{}'", words[2]));
        if (!itemType) fail(fmt::format("unknown type '{}'", words[3]));
        if (!isInteger(*countType))
          fail(fmt::format("list count type '{}' is not an integer type", words[2]));
        p.isList = true;
        p.countType = *countType;
        p.type = *itemType;
        p.name = std::string(words[4]);
      } else {
        if (words.size() != 3) fail("property line needs: property TYPE NAME");
        auto type = parseType(words[1]);
        if (!type) fail(fmt::format("unknown type '{}'", words[1]));
        p.type = *type;
        p.name = std::string(words[2]);
      }
      for (const Property& other : h.elements.back().properties)
        if (other.name == p.name)
          fail(fmt::format("property '{}' defined twice in element '{}'", p.name,
                           h.elements.back().name));
      h.elements.back().properties.push_back(std::move(p));
    } else if (key == "end_header") {
      sawEnd = true;
    } else {
      fail(fmt::format("unknown header keyword '{}'", key));
    }
  }
  if (!sawFormat) throw InputError(SourceLocation{in.name(), h.lines}, "header has no format line");
  return h;
}

// ------------------------------------------------------------------- decoding

template <typename T>
T loadScalar(const unsigned char* p, bool swap) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

double decode(Type t, const unsigned char* p, bool swap) {
  switch (t) {
    case Type::Int8:
      return double(int8_t(p[0]));
    case Type::Uint8:
      return double(p[0]);
    case Type::Int16:
      return double(loadScalar<int16_t>(p, swap));
    case Type::Uint16:
      return double(loadScalar<uint16_t>(p, swap));
    case Type::Int32:
      return double(loadScalar<int32_t>(p, swap));
    case Type::Uint32:
      return double(loadScalar<uint32_t>(p, swap));
    case Type::Float32:
      return double(loadScalar<float>(p, swap));
    case Type::Float64:
      return loadScalar<double>(p, swap);
  }
  return 0;
}

// Where each used vertex property lands; -1: not used.
struct VertexSlots {
  int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, u = -1, v = -1, radius = -1;
};

VertexSlots findVertexSlots(const Element& e) {
  VertexSlots s;
  auto find = [&](std::string_view name) {
    for (size_t i = 0; i < e.properties.size(); ++i)
      if (!e.properties[i].isList && e.properties[i].name == name) return int(i);
    return -1;
  };
  s.x = find("x");
  s.y = find("y");
  s.z = find("z");
  s.radius = find("radius");
  s.nx = find("nx");
  s.ny = find("ny");
  s.nz = find("nz");
  if (s.nx < 0 || s.ny < 0 || s.nz < 0) s.nx = s.ny = s.nz = -1;
  for (auto [u, v] : {std::pair{"u", "v"}, std::pair{"s", "t"}, std::pair{"texture_u", "texture_v"},
                      std::pair{"texture_s", "texture_t"}}) {
    int iu = find(u), iv = find(v);
    if (iu >= 0 && iv >= 0) {
      s.u = iu;
      s.v = iv;
      break;
    }
  }
  return s;
}

// Reads the body, one element after the other, in either encoding.
class BodyReader {
 public:
  BodyReader(ByteStream& in, const Header& header, const LoadOptions& options)
      : in_(in),
        header_(header),
        swap_((header.format == Format::BinaryBig) == (std::endian::native == std::endian::little)),
        line_(header.lines + 1),
        progress_(options, in.name(), in.size()) {}

  PlyContents read() {
    checkSizes();
    const Element* vertex = nullptr;
    for (const Element& e : header_.elements)
      if (e.name == "vertex") vertex = &e;
    if (!vertex) throw InputError(SourceLocation{in_.name(), header_.lines}, "no vertex element");
    vertexCount_ = vertex->count;
    if (vertexCount_ > kMaxElements)
      throw InputError(
          SourceLocation{in_.name(), vertex->line},
          fmt::format("{} vertices: more than 32-bit indices can address", vertexCount_));
    slots_ = findVertexSlots(*vertex);
    if (slots_.x < 0 || slots_.y < 0 || slots_.z < 0)
      throw InputError(SourceLocation{in_.name(), vertex->line},
                       "vertex element has no x, y and z properties");
    mesh_.positions.reserve(size_t(vertexCount_) + 1);  // Mesh::hasVertexSlack
    if (slots_.nx >= 0) mesh_.normals.reserve(size_t(vertexCount_));
    if (slots_.u >= 0) mesh_.uvs.reserve(size_t(vertexCount_));
    if (slots_.radius >= 0) radii_.reserve(size_t(vertexCount_));
    for (const Element& e : header_.elements) {
      if (&e == vertex) {
        readVertices(e);
      } else if (e.name == "face" || e.name == "tristrips") {
        readFaces(e, e.name == "tristrips");
      } else {
        skipElement(e);
      }
    }
    if (mesh_.indices.empty() && slots_.radius < 0)
      throw InputError(fmt::format(
          "{}: no faces and no vertex radius: nothing to render (a vertex-only file is particles "
          "when its vertices have a \"radius\")",
          in_.name()));
    if (!mesh_.indices.empty()) radii_.clear();  // a mesh's radii are not particles
    progress_.finish();
    return {std::move(mesh_), std::move(radii_)};
  }

 private:
  bool ascii() const { return header_.format == Format::Ascii; }

  // Before anything is allocated: can the bytes after the header hold what
  // the header promises?
  void checkSizes() {
    uint64_t available = in_.remaining();
    long double needed = 0;
    for (const Element& e : header_.elements) {
      long double perElement = 0;
      // Lists at their shortest: only the count (a face with fewer than
      // three indices is an error of its own, reported where it is).
      for (const Property& p : e.properties) {
        if (ascii()) {
          perElement += 2;
        } else {
          perElement += p.isList ? sizeOf(p.countType) : sizeOf(p.type);
        }
      }
      long double elementBytes = perElement * (long double)e.count;
      needed += elementBytes;
      // The last value of an ASCII file may lack its separator.
      long double slack = ascii() ? 1 : 0;
      if (needed - slack > (long double)available)
        throw InputError(
            SourceLocation{in_.name(), e.line},
            fmt::format("element '{}' with {} entries needs at least {:.0f} bytes{}, but only {} "
                        "bytes follow the header: truncated file or wrong count",
                        e.name, e.count, double(elementBytes),
                        &e == &header_.elements.front() ? "" : " after the elements before it",
                        available));
    }
  }

  [[noreturn]] void fail(const std::string& what) const {
    if (ascii()) throw InputError(SourceLocation{in_.name(), line_}, what);
    throw InputError(fmt::format("{}: {} (byte offset {})", in_.name(), what, in_.offset()));
  }

  [[noreturn]] void truncated(const Element& e, uint64_t index) {
    line_ = lastWordLine_;  // not the line after the last newline
    fail(fmt::format("file ends in {} {} of {}: truncated?", e.name, index, e.count));
  }

  // ASCII: the next whitespace-separated word; false at the end of the file.
  bool word(std::string& out) {
    out.clear();
    int c;
    while ((c = in_.peek()) >= 0 && (c == ' ' || c == '\t' || c == '\n' || c == '\r')) {
      if (c == '\n') ++line_;
      in_.get();
    }
    if (c >= 0) lastWordLine_ = line_;
    while ((c = in_.peek()) >= 0 && !(c == ' ' || c == '\t' || c == '\n' || c == '\r')) {
      if (c == 0) fail("NUL byte in an ASCII PLY body");
      if (out.size() > 64) fail(fmt::format("'{}...' is not a number", out.substr(0, 16)));
      out.push_back(char(c));
      in_.get();
    }
    return !out.empty();
  }

  double asciiNumber(Type t, const Element& e, uint64_t index, const Property& p) {
    if (!word(text_)) truncated(e, index);
    double d = 0;
    const char* b = text_.data();
    const char* end = b + text_.size();
    if (text_.size() > 1 && text_[0] == '+') ++b;
    auto [ptr, ec] = std::from_chars(b, end, d);
    if (ec == std::errc::result_out_of_range)
      d = std::strtod(text_.c_str(), nullptr);
    else if (ec != std::errc() || ptr != end)
      fail(fmt::format("{} {}: property '{}': '{}' is not a number", e.name, index, p.name, text_));
    if (isInteger(t) && std::isfinite(d) && d != std::floor(d))
      fail(fmt::format("{} {}: property '{}': '{}' is not an integer", e.name, index, p.name,
                       text_));
    return d;
  }

  double binaryNumber(Type t, const Element& e, uint64_t index) {
    unsigned char b[8];
    size_t n = size_t(sizeOf(t));
    if (in_.read(b, n) != n) truncated(e, index);
    return decode(t, b, swap_);
  }

  double number(Type t, const Element& e, uint64_t index, const Property& p) {
    return ascii() ? asciiNumber(t, e, index, p) : binaryNumber(t, e, index);
  }

  int64_t listCount(const Element& e, uint64_t index, const Property& p) {
    double c = number(p.countType, e, index, p);
    if (!(c >= 0))
      fail(fmt::format("{} {}: list '{}' has a negative length", e.name, index, p.name));
    // Each item takes at least one byte (binary) or two (ASCII).
    double most = double(in_.remaining()) / (ascii() ? 1.0 : double(sizeOf(p.type)));
    if (c > most + 1)
      fail(fmt::format("{} {}: list '{}' claims {:.0f} items, more than the rest of the file holds",
                       e.name, index, p.name, c));
    return int64_t(c);
  }

  void tick() {
    if ((++ticks_ & 4095) == 0) progress_.update(in_.offset());
  }

  void readVertices(const Element& e) {
    const size_t n = e.properties.size();
    std::vector<double> values(n, 0.0);
    bool fixed = true;
    size_t recordSize = 0;
    std::vector<size_t> offsets(n);
    for (size_t i = 0; i < n; ++i) {
      offsets[i] = recordSize;
      if (e.properties[i].isList) fixed = false;
      recordSize += size_t(sizeOf(e.properties[i].type));
    }
    std::vector<unsigned char> record(recordSize);
    for (uint64_t index = 0; index < e.count; ++index) {
      if (!ascii() && fixed) {
        if (in_.read(record.data(), recordSize) != recordSize) truncated(e, index);
        for (size_t i = 0; i < n; ++i)
          values[i] = decode(e.properties[i].type, record.data() + offsets[i], swap_);
      } else {
        for (size_t i = 0; i < n; ++i) {
          const Property& p = e.properties[i];
          if (p.isList) {
            int64_t count = listCount(e, index, p);
            for (int64_t k = 0; k < count; ++k) number(p.type, e, index, p);
          } else {
            values[i] = number(p.type, e, index, p);
          }
        }
      }
      Vec3f position{float(values[size_t(slots_.x)]), float(values[size_t(slots_.y)]),
                     float(values[size_t(slots_.z)])};
      if (!isFinite(position))
        fail(fmt::format("vertex {}: position ({}, {}, {}) is not finite", index,
                         values[size_t(slots_.x)], values[size_t(slots_.y)],
                         values[size_t(slots_.z)]));
      mesh_.positions.push_back(position);
      if (slots_.nx >= 0) {
        Vec3f normal{float(values[size_t(slots_.nx)]), float(values[size_t(slots_.ny)]),
                     float(values[size_t(slots_.nz)])};
        if (!isFinite(normal)) fail(fmt::format("vertex {}: normal is not finite", index));
        mesh_.normals.push_back(normal);
      }
      if (slots_.u >= 0) {
        Vec2f uv{float(values[size_t(slots_.u)]), float(values[size_t(slots_.v)])};
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
          fail(fmt::format("vertex {}: texture coordinate is not finite", index));
        mesh_.uvs.push_back(uv);
      }
      if (slots_.radius >= 0) {
        const auto radius = float(values[size_t(slots_.radius)]);
        if (!(radius > 0) || !std::isfinite(radius))
          fail(fmt::format("vertex {}: radius {} is not a positive number", index, radius));
        radii_.push_back(radius);
      }
      tick();
    }
  }

  int32_t vertexIndex(double raw, const Element& e, uint64_t index) {
    if (!(raw >= 0) || raw >= double(vertexCount_))
      fail(fmt::format("{} {}: vertex index {} out of range ({} vertices)", e.name, index, raw,
                       vertexCount_));
    return int32_t(raw);
  }

  void addTriangle(int32_t a, int32_t b, int32_t c) {
    if (mesh_.indices.size() >= kMaxElements)
      fail(fmt::format("more than {} triangles", kMaxElements));
    mesh_.indices.push_back({a, b, c});
  }

  void readFaces(const Element& e, bool strips) {
    int list = -1;
    for (size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].isList &&
          (e.properties[i].name == "vertex_indices" || e.properties[i].name == "vertex_index"))
        list = int(i);
    if (list < 0)
      throw InputError(SourceLocation{in_.name(), e.line},
                       fmt::format("element '{}' has no list property vertex_indices", e.name));
    if (!isInteger(e.properties[size_t(list)].type))
      throw InputError(SourceLocation{in_.name(), e.line},
                       fmt::format("{} vertex_indices must be integers", e.name));
    if (!strips) {
      // At least one triangle per face, but never more than the bytes left
      // can hold (three indices each), whatever the header says.
      const Property& p = e.properties[size_t(list)];
      uint64_t smallest = ascii() ? 8 : uint64_t(sizeOf(p.countType) + 3 * sizeOf(p.type));
      mesh_.indices.reserve(
          size_t(std::min({e.count, kMaxElements, in_.remaining() / smallest + 1})));
    }
    std::vector<int32_t> polygon;
    for (uint64_t index = 0; index < e.count; ++index) {
      for (size_t i = 0; i < e.properties.size(); ++i) {
        const Property& p = e.properties[i];
        if (!p.isList) {
          number(p.type, e, index, p);
          continue;
        }
        int64_t count = listCount(e, index, p);
        if (int(i) != list) {
          for (int64_t k = 0; k < count; ++k) number(p.type, e, index, p);
          continue;
        }
        if (strips) {
          readStrip(e, index, p, count);
          continue;
        }
        if (count < 3)
          fail(fmt::format("face {} has {} vertices (a face needs at least 3)", index, count));
        if (count > kMaxPolygon)
          fail(fmt::format("face {} has {} vertices: more than {}", index, count, kMaxPolygon));
        polygon.clear();
        for (int64_t k = 0; k < count; ++k)
          polygon.push_back(vertexIndex(number(p.type, e, index, p), e, index));
        for (size_t k = 1; k + 1 < polygon.size(); ++k)
          addTriangle(polygon[0], polygon[k], polygon[k + 1]);
      }
      tick();
    }
  }

  // Triangle strips with -1 between strips; every other triangle flipped so
  // that all keep the strip's orientation.
  void readStrip(const Element& e, uint64_t index, const Property& p, int64_t count) {
    int32_t a = -1, b = -1;
    int64_t inStrip = 0;
    for (int64_t k = 0; k < count; ++k) {
      double raw = number(p.type, e, index, p);
      if (raw == -1) {
        inStrip = 0;
        continue;
      }
      int32_t c = vertexIndex(raw, e, index);
      if (inStrip >= 2) {
        if (inStrip % 2 == 0)
          addTriangle(a, b, c);
        else
          addTriangle(b, a, c);
      }
      a = b;
      b = c;
      ++inStrip;
    }
  }

  void skipElement(const Element& e) {
    // An element without properties takes no bytes, however many it claims
    // (a fuzzer's 14444444444 of them took minutes to count through).
    if (e.properties.empty()) return;
    bool fixed = true;
    uint64_t recordSize = 0;
    for (const Property& p : e.properties) {
      if (p.isList) fixed = false;
      recordSize += uint64_t(sizeOf(p.type));
    }
    if (!ascii() && fixed) {
      uint64_t bytes = recordSize * e.count;
      if (in_.skip(bytes) != bytes)
        truncated(e, (in_.offset()) / std::max<uint64_t>(recordSize, 1));
      return;
    }
    for (uint64_t index = 0; index < e.count; ++index) {
      for (const Property& p : e.properties) {
        int64_t count = p.isList ? listCount(e, index, p) : 1;
        for (int64_t k = 0; k < count; ++k) number(p.type, e, index, p);
      }
      tick();
    }
  }

  ByteStream& in_;
  const Header& header_;
  bool swap_;
  int line_;
  int lastWordLine_ = 0;
  LoadProgress progress_;
  uint64_t vertexCount_ = 0;
  VertexSlots slots_;
  Mesh mesh_;
  std::vector<float> radii_;
  std::string text_;
  uint64_t ticks_ = 0;
};

}  // namespace

PlyContents readPlyContents(ByteStream& stream, const LoadOptions& options) {
  Header header = readHeader(stream);
  BodyReader body(stream, header, options);
  PlyContents contents = body.read();
  contents.mesh.name = std::filesystem::path(stream.name()).stem().string();
  return contents;
}

Mesh readPly(ByteStream& stream, const LoadOptions& options) {
  PlyContents contents = readPlyContents(stream, options);
  if (contents.mesh.indices.empty())
    throw InputError(fmt::format("{}: no faces: nothing to render as a mesh", stream.name()));
  return std::move(contents.mesh);
}

Mesh readPly(const std::string& path, const LoadOptions& options) {
  ByteStream stream = ByteStream::openFile(path);
  return readPly(stream, options);
}

Scene loadPlyScene(const std::string& path, const LoadOptions& options) {
  Scene scene;
  scene.name = std::filesystem::path(path).stem().string();
  ByteStream stream = ByteStream::openFile(path);
  PlyContents contents = readPlyContents(stream, options);
  Material grey;
  grey.name = "default";
  const int32_t material = scene.addMaterial(grey);
  if (contents.mesh.indices.empty()) {
    // Particles: a sphere at each vertex.
    std::vector<Vec3f> centres(contents.mesh.positions.begin(), contents.mesh.positions.end());
    scene.addSingleInstanceGeometry(
        {contents.mesh.name, material,
         std::make_shared<Spheres>(std::move(centres), std::move(contents.radii))});
  } else {
    contents.mesh.material = material;
    scene.addSingleInstanceMesh(std::move(contents.mesh));
  }
  addDefaultViewAndLights(scene);
  return scene;
}

}  // namespace ferry
