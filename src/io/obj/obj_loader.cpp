#include "io/obj/obj_loader.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include "core/error.h"
#include "io/default_lighting.h"
#include "io/images/image_io.h"
#include "material/metallic_roughness.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

constexpr size_t kMaxLineLength = size_t(16) << 20;
constexpr int64_t kMaxElements = INT32_MAX;  // 32-bit indices
constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";

// ------------------------------------------------------------------ text input

// Reads a text file a line at a time through a fixed buffer, so memory stays
// bounded whatever the file holds. Lines lose their "\n" or "\r\n".
class LineReader {
 public:
  explicit LineReader(std::string path)
      : path_(std::move(path)), file_(std::fopen(path_.c_str(), "rb"), &std::fclose) {
    if (!file_) throw InputError(fmt::format("{}: cannot open: {}", path_, std::strerror(errno)));
  }

  // False at the end of the file.
  bool next() {
    line_.clear();
    terminated_ = false;
    bool any = false;
    for (;;) {
      if (pos_ == end_) {
        if (eof_) break;
        end_ = std::fread(buffer_.data(), 1, buffer_.size(), file_.get());
        pos_ = 0;
        if (end_ == 0) {
          if (std::ferror(file_.get()))
            throw InputError(fmt::format("{}: read error: {}", path_, std::strerror(errno)));
          eof_ = true;
          break;
        }
      }
      any = true;
      const char* start = buffer_.data() + pos_;
      const void* newline = std::memchr(start, '\n', end_ - pos_);
      size_t n = newline ? size_t(static_cast<const char*>(newline) - start) : end_ - pos_;
      if (line_.size() + n > kMaxLineLength)
        throw InputError(SourceLocation{path_, number_ + 1},
                         "line longer than 16 MiB (not a text file?)");
      line_.append(start, n);
      pos_ += n;
      if (newline) {
        ++pos_;
        terminated_ = true;
        break;
      }
    }
    if (!any) return false;
    if (number_ == INT_MAX) throw InputError(fmt::format("{}: too many lines", path_));
    ++number_;
    if (!line_.empty() && line_.back() == '\r') line_.pop_back();
    if (number_ == 1 && std::string_view(line_).starts_with(kUtf8Bom))
      line_.erase(0, kUtf8Bom.size());
    if (std::memchr(line_.data(), '\0', line_.size()))
      throw InputError(where(), "NUL byte: this is not a text file");
    // tinyobjloader ends lines at a lone '\r' too; rejecting it keeps both passes
    // seeing the same lines.
    if (std::memchr(line_.data(), '\r', line_.size()))
      throw InputError(where(),
                       "carriage return inside a line (old Mac line endings are not supported)");
    return true;
  }

  std::string_view line() const { return line_; }
  // False only for a last line cut off without its newline.
  bool terminated() const { return terminated_; }
  SourceLocation where() const { return {path_, number_}; }

 private:
  std::string path_;
  std::unique_ptr<FILE, int (*)(FILE*)> file_;
  std::vector<char> buffer_ = std::vector<char>(size_t(1) << 16);
  size_t pos_ = 0, end_ = 0;
  bool eof_ = false;
  std::string line_;
  int number_ = 0;
  bool terminated_ = false;
};

// An input stream for tinyobjloader, past a UTF-8 byte order mark (LineReader skips it too).
std::ifstream openForTinyObj(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open: {}", path, std::strerror(errno)));
  char head[3] = {};
  in.read(head, 3);
  if (!(in.gcount() == 3 && std::string_view(head, 3) == kUtf8Bom)) {
    in.clear();
    in.seekg(0);
  }
  return in;
}

[[noreturn]] void failAt(const SourceLocation& where, const std::string& message) {
  throw InputError(where, message);
}

bool isBlank(char c) {
  return c == ' ' || c == '\t';
}

// Splits on blanks, the separators tinyobjloader uses; a token starting with
// '#' ends the statement (a trailing comment).
void splitStatement(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isBlank(line[i])) ++i;
    size_t begin = i;
    while (i < line.size() && !isBlank(line[i])) ++i;
    if (i > begin) {
      std::string_view token = line.substr(begin, i - begin);
      if (token.front() == '#' && !tokens.empty()) break;
      tokens.push_back(token);
    }
  }
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && isBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && isBlank(s.back())) s.remove_suffix(1);
  return s;
}

// The text after the first token (a keyword), without surrounding blanks.
std::string_view restOfLine(std::string_view line) {
  line = trim(line);
  size_t i = 0;
  while (i < line.size() && !isBlank(line[i])) ++i;
  return trim(line.substr(i));
}

enum class NumberStatus { Ok, NotANumber, NotFinite, TooLarge };

NumberStatus parseFloat(std::string_view token, float& out) {
  std::string_view s = token;
  if (s.size() > 1 && s[0] == '+' &&
      (std::isdigit(static_cast<unsigned char>(s[1])) || s[1] == '.'))
    s.remove_prefix(1);
  double d = 0;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
  if (s.empty() || ec == std::errc::invalid_argument || end != s.data() + s.size())
    return NumberStatus::NotANumber;
  if (ec == std::errc::result_out_of_range) {
    // Underflow is a harmless zero; overflow is not a number we can hold.
    d = std::strtod(std::string(s).c_str(), nullptr);
    if (std::isinf(d)) return NumberStatus::TooLarge;
  }
  if (!std::isfinite(d)) return NumberStatus::NotFinite;  // "nan", "inf"
  float f = static_cast<float>(d);
  if (!std::isfinite(f)) return NumberStatus::TooLarge;
  out = f;
  return NumberStatus::Ok;
}

bool parseInteger(std::string_view token, int64_t& out) {
  if (token.size() > 1 && token[0] == '+' && std::isdigit(static_cast<unsigned char>(token[1])))
    token.remove_prefix(1);
  auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  return !token.empty() && ec == std::errc() && end == token.data() + token.size();
}

// ------------------------------------------------------------------- materials

struct TextureRef {
  std::string name;      // as written in the MTL file
  fs::path path;         // resolved against the MTL file's directory
  SourceLocation where;  // the MTL line
  bool clamp = false;
};

struct MtlMaterial {
  std::string name;
  std::set<std::string, std::less<>> keys;  // statements present: values from tinyobj
  bool greyKd = false, greyKs = false, greyKe = false, greyTf = false;  // one value given
  std::optional<TextureRef> mapKd, mapD;
  tinyobj::material_t values{};
  bool used = false;
};

fs::path resolveRelative(const fs::path& dir, const std::string& name) {
  fs::path path = (dir / name).lexically_normal();
  std::error_code ec;
  if (!fs::exists(path, ec) && name.find('\\') != std::string::npos) {
    std::string slashed = name;
    std::replace(slashed.begin(), slashed.end(), '\\', '/');
    fs::path alternative = (dir / slashed).lexically_normal();
    if (fs::exists(alternative, ec)) return alternative;
  }
  return path;
}

fs::path directoryOf(const std::string& file) {
  fs::path dir = fs::path(file).parent_path();
  return dir.empty() ? fs::path(".") : dir;
}

// Every MTL file the OBJ names, validated line by line, with tinyobj's values.
class MaterialLibrary {
 public:
  std::vector<MtlMaterial> materials;

  bool loaded(const fs::path& file) const { return files_.count(file.string()) > 0; }
  bool empty() const { return files_.empty(); }
  std::string fileList() const {
    std::string s;
    for (const std::string& f : fileNames_) s += (s.empty() ? "" : ", ") + f;
    return s;
  }
  std::string nameList() const {
    std::string s;
    size_t shown = 0;
    for (const MtlMaterial& m : materials) {
      if (shown == 10) return s + ", ...";
      s += (s.empty() ? "" : ", ") + m.name;
      ++shown;
    }
    return s;
  }
  std::optional<int32_t> find(std::string_view name) const {
    auto it = byName_.find(std::string(name));
    if (it == byName_.end()) return std::nullopt;
    return it->second;
  }

  // Validates `file`, then parses it with tinyobj::LoadMtl.
  void load(const fs::path& file) {
    files_.insert(file.string());
    fileNames_.push_back(file.filename().string());
    const size_t first = materials.size();
    validate(file);
    const size_t defined = materials.size() - first;

    std::ifstream in = openForTinyObj(file.string());
    std::map<std::string, int> map;
    std::vector<tinyobj::material_t> parsed;
    std::string warning, error;
    tinyobj::LoadMtl(&map, &parsed, &in, &warning, &error);
    // LoadMtl makes one material per newmtl (or one unnamed one if there is none).
    if (defined == 0) return;
    if (parsed.size() != defined)
      throw InternalError(fmt::format("{}: tinyobjloader found {} materials, validation {}",
                                      file.string(), parsed.size(), defined));
    for (size_t i = 0; i < defined; ++i) materials[first + i].values = std::move(parsed[i]);
  }

  // Called at the first usemtl of a material: its textures must exist.
  void markUsed(int32_t index, const SourceLocation& usedAt) {
    MtlMaterial& m = materials[size_t(index)];
    if (m.used) return;
    m.used = true;
    for (const std::optional<TextureRef>* ref : {&m.mapKd, &m.mapD}) {
      if (!*ref) continue;
      std::error_code ec;
      fs::file_status status = fs::status((*ref)->path, ec);
      if (!fs::exists(status))
        throw InputError(
            (*ref)->where,
            fmt::format("texture '{}' not found (looked for {}; material '{}' used at {})",
                        (*ref)->name, (*ref)->path.string(), m.name, usedAt.toString()));
      if (!fs::is_regular_file(status))
        throw InputError((*ref)->where, fmt::format("texture '{}' ({}) is not a regular file",
                                                    (*ref)->name, (*ref)->path.string()));
    }
  }

 private:
  void validate(const fs::path& file) {
    LineReader reader(file.string());
    const fs::path dir = directoryOf(file.string());
    std::vector<std::string_view> tokens;
    MtlMaterial* current = nullptr;
    while (reader.next()) {
      auto where = reader.where();
      auto fail = [&where](const std::string& message) { failAt(where, message); };
      splitStatement(reader.line(), tokens);
      if (tokens.empty() || tokens[0].front() == '#') continue;
      const std::string_view keyword = tokens[0];
      const size_t count = tokens.size() - 1;

      auto parseNumbers = [&](const char* what) {
        for (size_t i = 1; i < tokens.size(); ++i) {
          float value;
          switch (parseFloat(tokens[i], value)) {
            case NumberStatus::Ok:
              break;
            case NumberStatus::NotANumber:
              failAt(where, fmt::format("{}: expected a number, found '{}'", what, tokens[i]));
            case NumberStatus::NotFinite:
              failAt(where, fmt::format("{}: value '{}' is not finite", what, tokens[i]));
            case NumberStatus::TooLarge:
              failAt(where, fmt::format("{}: value '{}' is too large for a 32-bit float", what,
                                        tokens[i]));
          }
        }
      };

      if (keyword == "newmtl") {
        std::string name(restOfLine(reader.line()));
        if (count == 0) fail("newmtl needs a material name");
        materials.push_back({});
        current = &materials.back();
        current->name = name;
        // The first definition wins, as in tinyobjloader.
        byName_.emplace(name, int32_t(materials.size() - 1));
        continue;
      }
      if (!current) continue;  // tinyobjloader drops statements before any newmtl

      if (keyword == "Ka" || keyword == "Kd" || keyword == "Ks" || keyword == "Ke" ||
          keyword == "Kt" || keyword == "Tf") {
        if (count > 0 && (tokens[1] == "spectral" || tokens[1] == "xyz"))
          fail(
              fmt::format("'{} {}' is not supported; write {} r g b", keyword, tokens[1], keyword));
        if (count != 1 && count != 3)
          fail(fmt::format("{} needs 1 or 3 numbers, found {}", keyword, count));
        parseNumbers(std::string(keyword).c_str());
        bool grey = count == 1;
        if (keyword == "Kd") current->greyKd = grey;
        if (keyword == "Ks") current->greyKs = grey;
        if (keyword == "Ke") current->greyKe = grey;
        if (keyword == "Kt" || keyword == "Tf") current->greyTf = grey;
        current->keys.insert(std::string(keyword == "Kt" ? "Tf" : keyword));
      } else if (keyword == "Ns" || keyword == "Ni" || keyword == "d" || keyword == "Tr" ||
                 keyword == "Pr" || keyword == "Pm" || keyword == "Ps" || keyword == "Pc" ||
                 keyword == "Pcr" || keyword == "aniso" || keyword == "anisor") {
        if (keyword == "d" && count > 0 && tokens[1] == "-halo") fail("'d -halo' is not supported");
        if (count != 1) fail(fmt::format("{} needs one number, found {}", keyword, count));
        parseNumbers(std::string(keyword).c_str());
        current->keys.insert(std::string(keyword));
      } else if (keyword == "illum") {
        int64_t model = -1;
        if (count != 1 || !parseInteger(tokens[1], model) || model < 0 || model > 10)
          fail(fmt::format("illum needs an integer from 0 to 10, found '{}'",
                           restOfLine(reader.line())));
        current->keys.insert("illum");
      } else if (keyword == "map_Kd" || keyword == "map_d") {
        std::string rest(restOfLine(reader.line()));
        std::string name;
        tinyobj::texture_option_t options{};
        if (rest.empty() || !tinyobj::ParseTextureNameAndOption(&name, &options, rest.c_str()) ||
            trim(name).empty())
          fail(fmt::format("{} needs a file name", keyword));
        TextureRef ref{name, resolveRelative(dir, name), reader.where(), options.clamp};
        (keyword == "map_Kd" ? current->mapKd : current->mapD) = std::move(ref);
      }
      // Anything else (map_Ks, bump, norm, ...) Ferry does not use.
    }
  }

  std::set<std::string> files_;
  std::vector<std::string> fileNames_;
  std::unordered_map<std::string, int32_t> byName_;
};

// --------------------------------------------------------- pass 1: validation

struct ObjCounts {
  int64_t positions = 0, uvs = 0, normals = 0, faces = 0;
  // Faces with a trailing '#' comment, as (face ordinal, vertex count): tinyobjloader
  // reads a comment's words as more vertices, and the builder drops them.
  std::vector<std::pair<int64_t, uint32_t>> commentedFaces;
};

struct ElementKind {
  const char* name;    // "vertex"
  const char* plural;  // "vertices"
};
constexpr ElementKind kPosition{"vertex", "vertices"};
constexpr ElementKind kUv{"texture coordinate", "texture coordinates"};
constexpr ElementKind kNormal{"normal", "normals"};

// mtllib names: blank-separated, "\ " is a blank inside a name, other
// backslashes are taken as path separators.
std::vector<std::string> splitLibraryNames(std::string_view rest) {
  std::vector<std::string> names;
  std::string current;
  for (size_t i = 0; i < rest.size(); ++i) {
    char c = rest[i];
    if (c == '\\' && i + 1 < rest.size() && isBlank(rest[i + 1])) {
      current += rest[++i];
    } else if (isBlank(c)) {
      if (!current.empty()) names.push_back(std::move(current));
      current.clear();
    } else {
      current += c == '\\' ? '/' : c;
    }
  }
  if (!current.empty()) names.push_back(std::move(current));
  return names;
}

class ObjValidator {
 public:
  ObjValidator(const std::string& path, MaterialLibrary& library)
      : path_(path), dir_(directoryOf(path)), library_(library), reader_(path) {}

  ObjCounts run() {
    while (reader_.next()) {
      std::string_view line = reader_.line();
      splitStatement(line, tokens_);
      if (tokens_.empty() || tokens_[0].front() == '#') continue;
      if (line.back() == '\\')
        fail("line continuation ('\\' at the end of a line) is not supported");
      const std::string_view keyword = tokens_[0];
      if (keyword == "v") {
        checkNumbers("vertex", 3, 7, "x y z [w] or x y z r g b");
        if (++counts_.positions > kMaxElements) fail("too many vertices for 32-bit indices");
      } else if (keyword == "vt") {
        checkNumbers("texture coordinate", 1, 3, "u [v [w]]");
        if (++counts_.uvs > kMaxElements) fail("too many texture coordinates for 32-bit indices");
      } else if (keyword == "vn") {
        checkNumbers("normal", 3, 3, "x y z");
        if (++counts_.normals > kMaxElements) fail("too many normals for 32-bit indices");
      } else if (keyword == "f") {
        checkReferences("face", 3);
        if (hasTrailingComment(line))
          counts_.commentedFaces.emplace_back(counts_.faces, uint32_t(tokens_.size() - 1));
        ++counts_.faces;
      } else if (keyword == "l") {
        checkReferences("line", 2);
      } else if (keyword == "p") {
        checkReferences("point", 1);
      } else if (keyword == "usemtl") {
        useMaterial(restOfLine(line));
      } else if (keyword == "mtllib") {
        loadLibraries(restOfLine(line));
      }
      // o, g, s and anything else: nothing to check.
    }
    if (counts_.faces == 0) throw InputError(SourceLocation{path_}, "no faces (nothing to render)");
    return counts_;
  }

 private:
  // Whether splitStatement stopped at a '#' token.
  static bool hasTrailingComment(std::string_view line) {
    for (size_t i = 1; i < line.size(); ++i)
      if (line[i] == '#' && isBlank(line[i - 1])) return true;
    return false;
  }

  [[noreturn]] void fail(const std::string& message) const {
    if (reader_.terminated()) throw InputError(reader_.where(), message);
    throw InputError(reader_.where(),
                     message + " (the file ends inside this line without a newline: truncated?)");
  }

  void checkNumbers(const char* what, size_t least, size_t most, const char* form) {
    const size_t count = tokens_.size() - 1;
    if (count < least)
      fail(fmt::format("{} needs {} number{} ({}), found {}", what, least, least > 1 ? "s" : "",
                       form, count));
    if (count > most) fail(fmt::format("{} has {} numbers, expected {}", what, count, form));
    for (size_t i = 1; i < tokens_.size(); ++i) {
      float value;
      switch (parseFloat(tokens_[i], value)) {
        case NumberStatus::Ok:
          break;
        case NumberStatus::NotANumber:
          fail(fmt::format("{}: expected a number, found '{}'", what, tokens_[i]));
        case NumberStatus::NotFinite:
          fail(fmt::format("{} value '{}' is not finite (NaN or infinity)", what, tokens_[i]));
        case NumberStatus::TooLarge:
          fail(fmt::format("{} value '{}' is too large for a 32-bit float", what, tokens_[i]));
      }
    }
  }

  void checkIndex(std::string_view token, std::string_view reference, const ElementKind& kind,
                  int64_t defined) {
    int64_t index = 0;
    if (!parseInteger(token, index)) {
      if (token == reference)
        fail(fmt::format("expected a {} index, found '{}'", kind.name, token));
      fail(fmt::format("expected a {} index, found '{}' in '{}'", kind.name, token, reference));
    }
    if (index == 0)
      fail(fmt::format("{} index 0{} is invalid (OBJ indices start at 1)", kind.name,
                       token == reference ? "" : fmt::format(" in '{}'", reference)));
    const char* noun = defined == 1 ? kind.name : kind.plural;
    if (index > defined)
      fail(fmt::format("{} index {} is out of range: {} {} defined above this line", kind.name,
                       index, defined, noun));
    if (index < -defined)
      fail(fmt::format("relative {} index {} is out of range: {} {} defined above this line",
                       kind.name, index, defined, noun));
  }

  void checkReferences(const char* what, size_t least) {
    const size_t count = tokens_.size() - 1;
    if (count < least)
      fail(fmt::format("{} needs at least {} vertices, found {}", what, least, count));
    for (size_t i = 1; i < tokens_.size(); ++i) {
      const std::string_view ref = tokens_[i];
      const size_t slash1 = ref.find('/');
      const size_t slash2 = slash1 == std::string_view::npos ? slash1 : ref.find('/', slash1 + 1);
      if (slash2 != std::string_view::npos && ref.find('/', slash2 + 1) != std::string_view::npos)
        fail(fmt::format("malformed vertex reference '{}' (expected v, v/vt, v//vn or v/vt/vn)",
                         ref));
      const std::string_view v = ref.substr(0, slash1);
      if (v.empty()) fail(fmt::format("malformed vertex reference '{}' (no vertex index)", ref));
      checkIndex(v, ref, kPosition, counts_.positions);
      if (slash1 == std::string_view::npos) continue;
      const std::string_view vt =
          ref.substr(slash1 + 1, slash2 == std::string_view::npos ? std::string_view::npos
                                                                  : slash2 - slash1 - 1);
      if (slash2 == std::string_view::npos && vt.empty())
        fail(fmt::format("malformed vertex reference '{}' (nothing after '/')", ref));
      if (!vt.empty()) checkIndex(vt, ref, kUv, counts_.uvs);
      if (slash2 == std::string_view::npos) continue;
      const std::string_view vn = ref.substr(slash2 + 1);
      if (vn.empty()) fail(fmt::format("malformed vertex reference '{}' (nothing after '/')", ref));
      checkIndex(vn, ref, kNormal, counts_.normals);
    }
  }

  void useMaterial(std::string_view name) {
    if (name.empty()) fail("usemtl needs a material name");
    std::optional<int32_t> index = library_.find(name);
    if (!index) {
      if (library_.empty())
        fail(fmt::format(
            "unknown material '{}': no material library (mtllib) is loaded above this line", name));
      fail(fmt::format("unknown material '{}' (not defined in {}; defined: {})", name,
                       library_.fileList(), library_.nameList()));
    }
    library_.markUsed(*index, reader_.where());
  }

  void loadLibraries(std::string_view rest) {
    std::vector<std::string> names = splitLibraryNames(rest);
    if (names.empty()) fail("mtllib needs a file name");
    for (const std::string& name : names) {
      fs::path file = resolveRelative(dir_, name);
      if (library_.loaded(file)) continue;
      std::error_code ec;
      fs::file_status status = fs::status(file, ec);
      if (!fs::exists(status))
        fail(fmt::format("material library '{}' not found (looked for {})", name, file.string()));
      if (!fs::is_regular_file(status))
        fail(fmt::format("material library '{}' ({}) is not a regular file", name, file.string()));
      library_.load(file);
    }
  }

  std::string path_;
  fs::path dir_;
  MaterialLibrary& library_;
  LineReader reader_;
  std::vector<std::string_view> tokens_;
  ObjCounts counts_;
};

// ------------------------------------------------------------ pass 2: building

struct CornerKey {
  int32_t v, vt, vn;  // 0-based; -1: absent
  bool operator==(const CornerKey&) const = default;
};

struct CornerKeyHash {
  size_t operator()(const CornerKey& k) const {
    uint64_t h = uint64_t(uint32_t(k.v)) * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t(uint32_t(k.vt)) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2));
    h ^= (uint64_t(uint32_t(k.vn)) + 0x8CB92BA72F3D8DD7ull + (h << 6) + (h >> 2));
    return size_t(h ^ (h >> 29));
  }
};

struct MeshBuilder {
  std::string shape;
  int32_t material = -1;  // index into MaterialLibrary::materials; -1: the default material
  Mesh mesh;
  std::vector<uint8_t> hasNormal;
  bool anyNormal = false, anyUv = false;
  std::unordered_map<CornerKey, uint32_t, CornerKeyHash> vertexOf;
};

class ObjBuilder {
 public:
  ObjBuilder(const std::string& path, const MaterialLibrary& library, const ObjCounts& counts)
      : path_(path), library_(library), commentedFaces_(counts.commentedFaces) {
    positions_.reserve(size_t(counts.positions));
    uvs_.reserve(size_t(counts.uvs));
    normals_.reserve(size_t(counts.normals));
  }

  void run(const ObjCounts& counts) {
    tinyobj::callback_t callbacks;
    callbacks.vertex_cb = [](void* self, tinyobj::real_t x, tinyobj::real_t y, tinyobj::real_t z,
                             tinyobj::real_t) {
      static_cast<ObjBuilder*>(self)->guard([&](ObjBuilder& b) {
        // Validation accepted only finite floats; this guards against the two
        // number parsers disagreeing.
        if (!isFinite(Vec3f(x, y, z)))
          throw InputError(
              fmt::format("{}: vertex {} is not finite", b.path_, b.positions_.size() + 1));
        b.positions_.push_back({x, y, z});
      });
    };
    callbacks.normal_cb = [](void* self, tinyobj::real_t x, tinyobj::real_t y, tinyobj::real_t z) {
      static_cast<ObjBuilder*>(self)->guard([&](ObjBuilder& b) {
        b.normals_.push_back({x, y, z});
      });
    };
    callbacks.texcoord_cb = [](void* self, tinyobj::real_t u, tinyobj::real_t v, tinyobj::real_t) {
      static_cast<ObjBuilder*>(self)->guard([&](ObjBuilder& b) { b.uvs_.push_back({u, v}); });
    };
    callbacks.index_cb = [](void* self, tinyobj::index_t* indices, int count) {
      static_cast<ObjBuilder*>(self)->guard([&](ObjBuilder& b) { b.addFace(indices, count); });
    };
    callbacks.usemtl_cb = [](void* self, const char* name, int) {
      static_cast<ObjBuilder*>(self)->guard([&](ObjBuilder& b) { b.useMaterial(name); });
    };
    callbacks.group_cb = [](void* self, const char** names, int count) {
      static_cast<ObjBuilder*>(self)->guard([&](ObjBuilder& b) {
        std::string shape;
        for (int i = 0; i < count; ++i) {
          if (i > 0) shape.push_back(' ');
          shape.append(names[i]);
        }
        b.setShape(shape);
      });
    };
    callbacks.object_cb = [](void* self, const char* name) {
      static_cast<ObjBuilder*>(self)->guard([&](ObjBuilder& b) { b.setShape(name); });
    };

    std::ifstream in = openForTinyObj(path_);
    std::string warning, error;
    // No MaterialReader: the libraries were loaded (and checked) by the validation pass.
    bool ok = tinyobj::LoadObjWithCallback(in, callbacks, this, nullptr, &warning, &error);
    if (failure_) std::rethrow_exception(failure_);
    if (!ok || !error.empty())
      throw InputError(
          fmt::format("{}: tinyobjloader: {}", path_, error.empty() ? "failed" : error));
    if (in.bad()) throw InputError(fmt::format("{}: read error", path_));
    if (int64_t(positions_.size()) != counts.positions || int64_t(uvs_.size()) != counts.uvs ||
        int64_t(normals_.size()) != counts.normals || faceOrdinal_ != counts.faces)
      throw InternalError(
          fmt::format("{}: validation counted {}/{}/{}/{} v/vt/vn/f, tinyobjloader {}/{}/{}/{}",
                      path_, counts.positions, counts.uvs, counts.normals, counts.faces,
                      positions_.size(), uvs_.size(), normals_.size(), faceOrdinal_));
  }

  std::vector<MeshBuilder>& meshes() { return meshes_; }

 private:
  template <typename F>
  void guard(F&& f) {
    if (failure_) return;
    try {
      f(*this);
    } catch (...) {
      failure_ = std::current_exception();
    }
  }

  void setShape(std::string_view name) {
    shape_ = std::string(trim(name));
    current_ = nullptr;
  }

  void useMaterial(std::string_view name) {
    std::optional<int32_t> index = library_.find(trim(name));
    if (!index)  // validation rejects this; only a disagreement with tinyobjloader gets here
      throw InputError(fmt::format("{}: unknown material '{}'", path_, trim(name)));
    material_ = *index;
    current_ = nullptr;
  }

  MeshBuilder& currentMesh() {
    if (current_) return *current_;
    auto key = std::make_pair(shape_, material_);
    auto it = meshIndex_.find(key);
    if (it == meshIndex_.end()) {
      it = meshIndex_.emplace(key, meshes_.size()).first;
      meshes_.emplace_back();
      meshes_.back().shape = shape_;
      meshes_.back().material = material_;
    }
    current_ = &meshes_[it->second];
    return *current_;
  }

  // OBJ indices (1-based, negative: relative) to 0-based; -1 when absent.
  int32_t resolve(int raw, size_t defined, const ElementKind& kind, bool required) const {
    if (raw == 0) {
      if (required) throw InputError(fmt::format("{}: face without a {} index", path_, kind.name));
      return -1;
    }
    int64_t index = raw > 0 ? int64_t(raw) - 1 : int64_t(defined) + raw;
    if (index < 0 || index >= int64_t(defined))
      throw InputError(fmt::format("{}: {} index {} out of range", path_, kind.name, raw));
    return int32_t(index);
  }

  uint32_t vertexFor(MeshBuilder& m, const CornerKey& key) {
    auto [it, inserted] = m.vertexOf.try_emplace(key, uint32_t(m.mesh.positions.size()));
    if (!inserted) return it->second;
    if (m.mesh.positions.size() >= size_t(kMaxElements))
      throw InputError(
          fmt::format("{}: mesh '{}' has too many vertices for 32-bit indices", path_, m.shape));
    m.mesh.positions.push_back(positions_[size_t(key.v)]);
    Vec3f normal(0);
    bool hasNormal = false;
    if (key.vn >= 0) {
      Vec3f n = normals_[size_t(key.vn)];
      float len = length(n);
      if (std::isfinite(len) && len > 1e-20f) {
        normal = n / len;
        hasNormal = true;
      }
    }
    m.mesh.normals.push_back(normal);
    m.hasNormal.push_back(hasNormal);
    m.anyNormal |= hasNormal;
    m.mesh.uvs.push_back(key.vt >= 0 ? uvs_[size_t(key.vt)] : Vec2f(0, 0));
    m.anyUv |= key.vt >= 0;
    return it->second;
  }

  void addFace(const tinyobj::index_t* indices, int count) {
    corners_.clear();
    int vertices = count;
    if (nextCommented_ < commentedFaces_.size() &&
        commentedFaces_[nextCommented_].first == faceOrdinal_)
      vertices = std::min(count, int(commentedFaces_[nextCommented_++].second));
    ++faceOrdinal_;
    for (int i = 0; i < vertices; ++i) {
      corners_.push_back({resolve(indices[i].vertex_index, positions_.size(), kPosition, true),
                          resolve(indices[i].texcoord_index, uvs_.size(), kUv, false),
                          resolve(indices[i].normal_index, normals_.size(), kNormal, false)});
    }
    if (corners_.size() < 3)
      throw InputError(fmt::format("{}: face with fewer than 3 vertices", path_));
    MeshBuilder& m = currentMesh();
    ids_.clear();
    for (const CornerKey& c : corners_) ids_.push_back(vertexFor(m, c));
    auto triangle = [&](size_t a, size_t b, size_t c) {
      m.mesh.indices.push_back({int32_t(ids_[a]), int32_t(ids_[b]), int32_t(ids_[c])});
    };
    if (ids_.size() == 4) {
      // Split along the shorter diagonal, as tinyobjloader does.
      auto p = [&](size_t i) { return positions_[size_t(corners_[i].v)]; };
      Vec3f d02 = p(2) - p(0), d13 = p(3) - p(1);
      if (dot(d02, d02) < dot(d13, d13)) {
        triangle(0, 1, 2);
        triangle(0, 2, 3);
      } else {
        triangle(0, 1, 3);
        triangle(1, 2, 3);
      }
    } else {
      for (size_t i = 1; i + 1 < ids_.size(); ++i) triangle(0, i, i + 1);
    }
  }

  std::string path_;
  const MaterialLibrary& library_;
  std::vector<Vec3f> positions_, normals_;
  std::vector<Vec2f> uvs_;
  std::string shape_;
  int32_t material_ = -1;
  std::map<std::pair<std::string, int32_t>, size_t> meshIndex_;
  std::vector<MeshBuilder> meshes_;  // in order of first face
  MeshBuilder* current_ = nullptr;
  std::vector<CornerKey> corners_;
  std::vector<uint32_t> ids_;
  const std::vector<std::pair<int64_t, uint32_t>>& commentedFaces_;
  size_t nextCommented_ = 0;
  int64_t faceOrdinal_ = 0;
  std::exception_ptr failure_;
};

// Drops absent attributes, fills the gaps in partial ones, frees the build maps.
void finishMesh(MeshBuilder& m) {
  m.vertexOf = {};
  Mesh& mesh = m.mesh;
  if (!m.anyUv) mesh.uvs = {};
  if (!m.anyNormal) {
    mesh.normals = {};
  } else {
    for (const Vec3i& t : mesh.indices) {
      Vec3f p0 = mesh.positions[size_t(t.x)], p1 = mesh.positions[size_t(t.y)],
            p2 = mesh.positions[size_t(t.z)];
      Vec3f areaNormal = cross(p1 - p0, p2 - p0);  // length: twice the area
      for (int k = 0; k < 3; ++k)
        if (!m.hasNormal[size_t(t[k])]) mesh.normals[size_t(t[k])] += areaNormal;
    }
    for (size_t v = 0; v < mesh.normals.size(); ++v) {
      if (m.hasNormal[v]) continue;
      float len = length(mesh.normals[v]);
      mesh.normals[v] = std::isfinite(len) && len > 0 ? mesh.normals[v] / len : Vec3f(0, 0, 1);
    }
  }
  m.hasNormal = {};
  mesh.positions.shrink_to_fit();
  mesh.normals.shrink_to_fit();
  mesh.uvs.shrink_to_fit();
  mesh.indices.shrink_to_fit();
}

// ------------------------------------------------------------ scene assembly

class MaterialConverter {
 public:
  MaterialConverter(Scene& scene, const MaterialLibrary& library)
      : scene_(scene), library_(library), sceneIndex_(library.materials.size(), -1) {}

  int32_t materialFor(int32_t libraryIndex) {
    if (libraryIndex < 0) {
      if (defaultMaterial_ < 0) {
        Material m;
        m.name = "default";
        defaultMaterial_ = scene_.addMaterial(m);
      }
      return defaultMaterial_;
    }
    int32_t& index = sceneIndex_[size_t(libraryIndex)];
    if (index < 0) index = scene_.addMaterial(convert(library_.materials[size_t(libraryIndex)]));
    return index;
  }

 private:
  Material convert(const MtlMaterial& r) {
    const tinyobj::material_t& v = r.values;
    auto has = [&](std::string_view key) { return r.keys.count(key) > 0; };
    auto color = [](const tinyobj::real_t c[3], bool grey) {
      return grey ? Vec3f(c[0]) : Vec3f(c[0], c[1], c[2]);
    };
    auto clamp01 = [](Vec3f c) { return min(max(c, Vec3f(0)), Vec3f(1)); };
    const int illum = has("illum") ? v.illum : -1;

    Material m;
    m.name = r.name;
    if (has("Kd"))
      m.baseColor = clamp01(color(v.diffuse, r.greyKd));
    else if (r.mapKd)
      m.baseColor = Vec3f(1);
    if (has("Ke")) m.emission = max(color(v.emission, r.greyKe), Vec3f(0));
    MetallicRoughness surface;
    if (has("Pr"))
      surface.roughness = std::clamp(float(v.roughness), 0.0f, 1.0f);
    else if (has("Ns"))
      surface.roughness = std::sqrt(2.0f / (std::max(float(v.shininess), 0.0f) + 2.0f));
    if (has("Pm")) {
      surface.metallic = std::clamp(float(v.metallic), 0.0f, 1.0f);
    } else if (illum == 3 || illum == 5) {
      surface.metallic = 1;
      Vec3f ks = has("Ks") ? clamp01(color(v.specular, r.greyKs)) : Vec3f(0);
      if (maxComponent(ks) > 0) m.baseColor = ks;
    }
    if (has("Ni") && v.ior >= 1) surface.ior = float(v.ior);
    float transmission = 0;
    if (has("d") || has("Tr")) transmission = 1 - std::clamp(float(v.dissolve), 0.0f, 1.0f);
    if ((illum == 4 || illum == 6 || illum == 7) && has("Tf"))
      transmission =
          std::max(transmission, maxComponent(clamp01(color(v.transmittance, r.greyTf))));
    surface.transmission = transmission;
    m.model = modelOf(surface);
    if (r.mapKd) m.baseColorTexture = textureFor(*r.mapKd, false);
    if (r.mapD) m.alphaTexture = textureFor(*r.mapD, true);
    return m;
  }

  int32_t textureFor(const TextureRef& ref, bool alpha) {
    std::string key =
        fmt::format("{}|{}|{}", alpha ? 'a' : 'c', ref.clamp ? 'c' : 'r', ref.path.string());
    auto it = textures_.find(key);
    if (it != textures_.end()) return it->second;
    Texture texture;
    try {
      texture = alpha ? readAlphaTexture(ref.path.string()) : readTexture(ref.path.string());
    } catch (const InputError& e) {
      throw InputError(ref.where, fmt::format("texture '{}': {}", ref.name, e.what()));
    }
    texture.wrap = ref.clamp ? WrapMode::Clamp : WrapMode::Repeat;
    scene_.textures.push_back(std::move(texture));
    int32_t index = int32_t(scene_.textures.size() - 1);
    textures_.emplace(key, index);
    return index;
  }

  Scene& scene_;
  const MaterialLibrary& library_;
  std::vector<int32_t> sceneIndex_;
  int32_t defaultMaterial_ = -1;
  std::unordered_map<std::string, int32_t> textures_;
};

}  // namespace

Scene loadObj(const std::string& path) {
  std::error_code ec;
  fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) throw InputError(fmt::format("{}: no such file", path));
  if (!fs::is_regular_file(status)) throw InputError(fmt::format("{}: not a regular file", path));

  MaterialLibrary library;
  ObjCounts counts = ObjValidator(path, library).run();

  Scene scene;
  scene.name = fs::path(path).stem().string();
  {
    ObjBuilder builder(path, library, counts);
    builder.run(counts);
    MaterialConverter materials(scene, library);
    for (MeshBuilder& m : builder.meshes()) {
      finishMesh(m);
      std::string shape = m.shape.empty() ? scene.name : m.shape;
      m.mesh.name =
          m.material < 0 ? shape : shape + "/" + library.materials[size_t(m.material)].name;
      m.mesh.material = materials.materialFor(m.material);
      scene.addSingleInstanceMesh(std::move(m.mesh));
      m = MeshBuilder{};  // free as we go
    }
  }
  addDefaultViewAndLights(scene);
  return scene;
}

}  // namespace ferry
