#include "io/parts/part_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <type_traits>

#include "core/error.h"
#include "core/hash64.h"
#include "io/images/image_io.h"
#include "material/models/coated_conductor.h"
#include "material/models/coated_diffuse.h"
#include "material/models/conductor.h"
#include "material/models/dielectric.h"
#include "material/models/diffuse.h"
#include "material/models/diffuse_transmission.h"
#include "material/models/fourier.h"
#include "material/models/fresnel_blend.h"
#include "shapes/shape_kinds.h"

namespace ferry {
namespace {

static_assert(std::endian::native == std::endian::little, "part files are little-endian");
static_assert(std::is_trivially_copyable_v<Vec3f> && sizeof(Vec3f) == 12);
static_assert(std::is_trivially_copyable_v<Vec2f> && sizeof(Vec2f) == 8);
static_assert(std::is_trivially_copyable_v<Vec3i> && sizeof(Vec3i) == 12);
static_assert(std::is_trivially_copyable_v<Box3f> && sizeof(Box3f) == 24);
// A proxy as format 1 stored it.
struct ProxyV1 {
  Box3f bounds;
  uint64_t owners;
};
static_assert(std::is_trivially_copyable_v<ProxyV1> && sizeof(ProxyV1) == 32);
static_assert(std::is_trivially_copyable_v<Affine3f> && sizeof(Affine3f) == 48);
// The writers below list every field of these structs: when one gains a
// field, these fail so that the part format (and kPartFormatVersion) follows.
static_assert(sizeof(Material) == 112,
              "Material changed: update part_file.cpp and kPartFormatVersion");
// (Mesh::stored is not written: a part holds its meshes' arrays; 136 before
// it; the arrays became SharedArrays at 392, and 192 for Texture, same
// fields; Texture is 296 with its combination.
// Mesh::media is not written either: part files refuse scenes with media,
// but for the media inside subsurface materials, which they drop.)
static_assert(sizeof(Mesh) == 400, "Mesh changed: update part_file.cpp and kPartFormatVersion");
static_assert(sizeof(CameraView) == 104,  // 88 before its motion (format 14)
              "CameraView changed: update part_file.cpp and kPartFormatVersion");
static_assert(sizeof(Instance) == 72,  // 52 before its motion (format 14)
              "Instance changed: update part_file.cpp and kPartFormatVersion");
static_assert(sizeof(MotionKey) == 64,
              "MotionKey changed: update part_file.cpp and kPartFormatVersion");
static_assert(sizeof(Texture) == 296,
              "Texture changed: update part_file.cpp and kPartFormatVersion");
static_assert(sizeof(Affine3f) == 48,
              "Affine3f changed: update part_file.cpp and kPartFormatVersion");
static_assert(sizeof(SunLight) == 28,
              "SunLight changed: update part_file.cpp and kPartFormatVersion");

constexpr char kMagic[8] = {'F', 'E', 'R', 'R', 'Y', 'P', 'R', 'T'};
constexpr uint32_t kKindPart = 1;
constexpr uint32_t kKindShared = 2;
constexpr size_t kHeaderBytes = 64;
constexpr size_t kHashedHeaderBytes = 40;
constexpr uint32_t kEndMarker = 0xF0E1D2C3u;

struct Header {
  char magic[8];
  uint32_t version;
  uint32_t kind;
  uint64_t fileBytes;
  uint64_t payloadHash;
  uint32_t rank;
  uint32_t ranks;
  uint64_t headerHash;  // of the 40 bytes before it
  uint8_t reserved[16];
};
static_assert(sizeof(Header) == kHeaderBytes && offsetof(Header, headerHash) == kHashedHeaderBytes);

// ------------------------------------------------------------------ writing

class FileWriter {
 public:
  explicit FileWriter(const std::string& path)
      : path_(path), file_(std::fopen(path.c_str(), "wb"), &std::fclose) {
    if (!file_) throw InputError(fmt::format("{}: cannot write ({})", path, std::strerror(errno)));
    std::setvbuf(file_.get(), nullptr, _IOFBF, 1 << 20);
    Header blank{};
    put(&blank, sizeof(blank), false);
  }

  template <typename T>
  void pod(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(&value, sizeof(T), true);
  }
  void str(const std::string& s) {
    pod(uint32_t(s.size()));
    put(s.data(), s.size(), true);
  }
  // Count, then the elements, 16-byte aligned in the file.
  template <typename T>
  void array(const T* data, size_t count) {
    static_assert(std::is_trivially_copyable_v<T>);
    pod(uint64_t(count));
    static const uint8_t zeros[16] = {};
    if (offset_ % 16) put(zeros, 16 - offset_ % 16, true);
    put(data, count * sizeof(T), true);
  }
  template <typename Array>  // std::vector or SharedArray
  void array(const Array& v) {
    array(v.data(), v.size());
  }

  WrittenFile finish(uint32_t kind, uint32_t rank, uint32_t ranks) {
    pod(kEndMarker);
    Header h{};
    std::memcpy(h.magic, kMagic, sizeof(kMagic));
    h.version = kPartFormatVersion;
    h.kind = kind;
    h.fileBytes = offset_;
    h.payloadHash = hash_.digest();
    h.rank = rank;
    h.ranks = ranks;
    h.headerHash = hash64(&h, kHashedHeaderBytes);
    if (std::fflush(file_.get()) != 0 || std::fseek(file_.get(), 0, SEEK_SET) != 0 ||
        std::fwrite(&h, sizeof(h), 1, file_.get()) != 1 || std::fflush(file_.get()) != 0)
      fail();
    return {h.fileBytes, h.payloadHash};
  }

 private:
  void put(const void* data, size_t bytes, bool hashed) {
    if (bytes == 0) return;
    if (std::fwrite(data, 1, bytes, file_.get()) != bytes) fail();
    if (hashed) hash_.update(data, bytes);
    offset_ += bytes;
  }
  [[noreturn]] void fail() {
    throw InputError(fmt::format("{}: write failed ({})", path_, std::strerror(errno)));
  }

  std::string path_;
  std::unique_ptr<FILE, int (*)(FILE*)> file_;
  Hash64 hash_;
  uint64_t offset_ = 0;
};

// A material: what every surface has, then its model by name and the
// model's own record (material/material_model.h); `tableIndex` renumbers the
// tables the model names.
void writeMaterial(FileWriter& w, const Material& m,
                   const MaterialRecordWriter::TableIndex& tableIndex) {
  w.str(m.name);
  w.pod(m.baseColor);
  w.pod(m.baseColorTexture);
  w.pod(m.emission);
  w.pod(m.alphaTexture);
  w.pod(m.alphaCutoff);
  // Bits 0, 1: the emitter's sides; 2, 3: the alpha test; 4, 5: the rays it cuts.
  w.pod(uint8_t((m.emitsBackSide ? 1 : 0) | (m.lightSampledOnBackSide ? 2 : 0) |
                (uint8_t(m.alphaTest) << 2) | (uint8_t(m.alphaRays) << 4)));
  w.pod(m.bumpTexture);
  w.pod(m.bumpScale);
  w.pod(m.normalTexture);
  w.pod(m.normalScale);
  w.pod(m.mixedWith);
  w.pod(m.mixAmount);
  w.str(std::string(m.model->name()));
  MaterialRecordWriter record(tableIndex);
  m.model->write(record);
  w.array(record.bytes());
}

// The table as read (a0 and recip are derived again when read back).
void writeBsdfTable(FileWriter& w, const FourierBsdfTable& t) {
  w.str(t.name);
  w.pod(t.nMu);
  w.pod(t.nChannels);
  w.pod(t.mMax);
  w.pod(t.eta);
  w.array(t.mu);
  w.array(t.cdf);
  w.array(t.offset);
  w.array(t.order);
  w.array(t.coefficients);
}

void writeTexture(FileWriter& w, const Texture& t) {
  w.str(t.name);
  w.pod(int32_t(t.width));
  w.pod(int32_t(t.height));
  w.pod(uint8_t(t.wrap));
  w.pod(uint8_t(t.srgb));
  w.array(t.rgba);
  w.pod(uint8_t(t.solid.kind));
  w.pod(t.solid.worldToTexture);
  w.pod(t.solid.octaves);
  w.pod(t.solid.omega);
  w.pod(t.solid.scale);
  w.pod(t.solid.variation);
  w.pod(uint8_t(t.combination));
  w.pod(t.mapping);
  for (const TextureOperand& o : t.operands) {
    w.pod(o.constant);
    w.pod(o.part);
  }
  w.pod(uint32_t(t.parts.size()));
  for (const Texture& part : t.parts) writeTexture(w, part);
}

void writeMesh(FileWriter& w, const Mesh& m, int32_t material) {
  w.str(m.name);
  w.pod(material);
  w.array(m.positions);
  w.array(m.normals);
  w.array(m.uvs);
  w.array(m.indices);
}

// The listed instances of `scene` and what they use, re-indexed; `owners`
// (per scene instance) written alongside when given.
void writeContent(FileWriter& w, const Scene& scene, const std::vector<int32_t>& instances,
                  const std::vector<RankSet>* owners, size_t ownerWords) {
  std::vector<int32_t> objectIndex(scene.objects.size(), -1), meshIndex(scene.meshes.size(), -1),
      materialIndex(scene.materials.size(), -1), textureIndex(scene.textures.size(), -1),
      tableIndex(scene.bsdfTables.size(), -1), geometryIndex(scene.geometries.size(), -1);
  for (int32_t i : instances) objectIndex[scene.instances[i].object] = 0;
  for (size_t o = 0; o < scene.objects.size(); ++o)
    if (objectIndex[o] == 0) {
      for (int32_t m : scene.objects[o].meshes) meshIndex[m] = 0;
      for (int32_t g : scene.objects[o].geometries) geometryIndex[g] = 0;
    }
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    if (meshIndex[m] == 0)
      scene.forEachShadingMaterial(scene.meshes[m].material,
                                   [&](int32_t k) { materialIndex[size_t(k)] = 0; });
  for (size_t g = 0; g < scene.geometries.size(); ++g)
    if (geometryIndex[g] == 0)
      scene.forEachShadingMaterial(scene.geometries[g].material,
                                   [&](int32_t k) { materialIndex[size_t(k)] = 0; });
  for (size_t k = 0; k < scene.materials.size(); ++k)
    if (materialIndex[k] == 0) {
      for (int32_t t : scene.materials[k].textures())
        if (t != kNoTexture) textureIndex[t] = 0;
      if (const int32_t t = scene.materials[k].bsdfTable(); t != kNoBsdfTable)
        tableIndex[size_t(t)] = 0;
    }
  // Kept items get new indices in their original order.
  auto number = [](std::vector<int32_t>& index) {
    int32_t next = 0;
    for (int32_t& x : index)
      if (x == 0) x = next++;
    return next;
  };
  const int32_t objects = number(objectIndex), meshes = number(meshIndex),
                materials = number(materialIndex), textures = number(textureIndex),
                tables = number(tableIndex), geometries = number(geometryIndex);

  w.pod(uint64_t(textures));
  for (size_t t = 0; t < scene.textures.size(); ++t)
    if (textureIndex[t] >= 0) writeTexture(w, scene.textures[t]);
  w.pod(uint64_t(tables));
  for (size_t t = 0; t < scene.bsdfTables.size(); ++t)
    if (tableIndex[t] >= 0) writeBsdfTable(w, *scene.bsdfTables[t]);
  w.pod(uint64_t(materials));
  for (size_t k = 0; k < scene.materials.size(); ++k)
    if (materialIndex[k] >= 0) {
      Material mat = scene.materials[k];
      for (int32_t* t : mat.textureSlots())
        if (*t != kNoTexture) *t = textureIndex[*t];
      if (mat.mixedWith >= 0) mat.mixedWith = materialIndex[size_t(mat.mixedWith)];
      writeMaterial(w, mat,
                    [&](int32_t t) { return t == kNoBsdfTable ? t : tableIndex[size_t(t)]; });
    }
  w.pod(uint64_t(meshes));
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    if (meshIndex[m] >= 0) {
      Mesh scratch;  // a stored mesh is read back for as long as it is written
      writeMesh(w, scene.geometry(int32_t(m), scratch), materialIndex[scene.meshes[m].material]);
    }
  w.pod(uint64_t(geometries));
  for (size_t g = 0; g < scene.geometries.size(); ++g)
    if (geometryIndex[g] >= 0) {
      const Geometry& geometry = scene.geometries[g];
      FERRY_CHECK(geometry.shape != nullptr);  // a part holds what it names
      w.str(geometry.name);
      w.pod(materialIndex[size_t(geometry.material)]);
      w.str(std::string(geometry.shape->kind()));
      RecordWriter record;
      geometry.shape->write(record);
      w.array(record.bytes());
    }
  w.pod(uint64_t(objects));
  std::vector<int32_t> list;
  for (size_t o = 0; o < scene.objects.size(); ++o)
    if (objectIndex[o] >= 0) {
      w.str(scene.objects[o].name);
      list.clear();
      for (int32_t m : scene.objects[o].meshes) list.push_back(meshIndex[m]);
      w.array(list);
      list.clear();
      for (int32_t g : scene.objects[o].geometries) list.push_back(geometryIndex[g]);
      w.array(list);
    }
  std::vector<int32_t> instanceObjects;
  std::vector<Affine3f> transforms;
  std::vector<uint64_t> masks;
  for (int32_t i : instances) {
    instanceObjects.push_back(objectIndex[scene.instances[i].object]);
    transforms.push_back(scene.instances[i].transform);
    for (size_t k = 0; k < ownerWords; ++k) masks.push_back(owners ? (*owners)[i].word(k) : 0);
  }
  w.array(instanceObjects);
  w.array(transforms);
  w.array(masks);
  // Format 14: each instance's motion keys (a count, 0 when it does not move).
  std::vector<uint32_t> keyCounts;
  std::vector<MotionKey> keys;
  for (int32_t i : instances) {
    const auto& motion = scene.instances[i].motion;
    keyCounts.push_back(motion ? uint32_t(motion->keys().size()) : 0);
    if (motion) keys.insert(keys.end(), motion->keys().begin(), motion->keys().end());
  }
  w.array(keyCounts);
  w.array(keys);
}

void writeLights(FileWriter& w, const Scene& lights) {
  std::vector<int32_t> all(lights.instances.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = int32_t(i);
  writeContent(w, lights, all, nullptr, 1);
  w.pod(uint64_t(lights.suns.size()));
  for (const SunLight& s : lights.suns) {
    w.pod(s.direction);
    w.pod(s.irradiance);
    w.pod(s.angularRadius);
  }
  const EnvironmentLight& env = lights.environment;
  w.pod(env.color);
  w.pod(env.rotation);
  w.pod(uint8_t(env.image ? 1 : 0));
  if (env.image) {
    w.str(env.image->name);
    w.pod(int32_t(env.image->width));
    w.pod(int32_t(env.image->height));
    w.array(env.image->pixels);
  }
  w.pod(uint64_t(lights.pointLights.size()));
  for (const PointLight& l : lights.pointLights) {
    w.pod(l.position);
    w.pod(l.intensity);
    w.pod(l.direction);
    w.pod(l.cosTotalWidth);
    w.pod(l.cosFalloffStart);
    w.pod(uint8_t(l.falloff));
  }
}

// ------------------------------------------------------------------ reading

class MappedFile {
 public:
  explicit MappedFile(const std::string& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) {
      if (errno == ENOENT) throw InputError(fmt::format("{}: no such file", path));
      throw InputError(fmt::format("{}: cannot open ({})", path, std::strerror(errno)));
    }
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd_);
      throw InputError(fmt::format("{}: not a regular file", path));
    }
    size_ = uint64_t(st.st_size);
    if (size_ > 0) {
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd_, 0);
      if (p == MAP_FAILED) {
        ::close(fd_);
        throw InputError(fmt::format("{}: cannot map ({})", path, std::strerror(errno)));
      }
      data_ = static_cast<const uint8_t*>(p);
      ::madvise(p, size_, MADV_SEQUENTIAL);
    }
  }
  ~MappedFile() {
    if (data_) ::munmap(const_cast<uint8_t*>(data_), size_);
    if (fd_ >= 0) ::close(fd_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const uint8_t* data() const { return data_; }
  uint64_t size() const { return size_; }
  // Lets the kernel drop the pages of [begin, end) from this process (they
  // stay in the page cache): what has been copied need not stay resident.
  void release(uint64_t begin, uint64_t end) const {
    const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
    uint64_t from = (begin + page - 1) / page * page, to = end / page * page;
    if (data_ && to > from) ::madvise(const_cast<uint8_t*>(data_) + from, to - from, MADV_DONTNEED);
  }
  // Rendering reads the shared arrays at hits, in no order (was sequential for the hash check).
  void adviseRandomAccess() const {
    if (data_) ::madvise(const_cast<uint8_t*>(data_), size_, MADV_NORMAL);
  }

 private:
  std::string path_;
  int fd_ = -1;
  const uint8_t* data_ = nullptr;
  uint64_t size_ = 0;
};

// Checks the header and the hashes; returns the header.
Header checkFile(const MappedFile& file, const std::string& path, uint32_t kind,
                 uint64_t expectedHash) {
  auto bad = [&](const std::string& what) { return InputError(fmt::format("{}: {}", path, what)); };
  if (file.size() < kHeaderBytes)
    throw bad(fmt::format("truncated: {} bytes, less than a part file's header", file.size()));
  Header h;
  std::memcpy(&h, file.data(), sizeof(h));
  if (std::memcmp(h.magic, kMagic, sizeof(kMagic)) != 0) throw bad("not a Ferry part file");
  if (h.version < kOldestPartFormatVersion || h.version > kPartFormatVersion)
    throw bad(fmt::format(
        "made by another version of Ferry (part format {}, this Ferry reads formats {} to {}): "
        "partition the scene again",
        h.version, kOldestPartFormatVersion, kPartFormatVersion));
  if (hash64(&h, kHashedHeaderBytes) != h.headerHash) throw bad("corrupt header (hash mismatch)");
  if (h.kind != kind)
    throw bad(kind == kKindPart ? "is a shared file, not a rank's part"
                                : "is a rank's part, not the shared file");
  if (h.fileBytes != file.size())
    throw bad(h.fileBytes > file.size()
                  ? fmt::format("truncated: {} of {} bytes", file.size(), h.fileBytes)
                  : fmt::format("{} bytes, {} more than written", file.size(),
                                file.size() - h.fileBytes));
  Hash64 hash;
  constexpr uint64_t kChunk = 64ull << 20;
  for (uint64_t at = kHeaderBytes; at < file.size(); at += kChunk) {
    const uint64_t n = std::min(kChunk, file.size() - at);
    hash.update(file.data() + at, n);
    file.release(at, at + n);
  }
  file.adviseRandomAccess();  // the arrays stay mapped for rendering: no early eviction
  if (hash.digest() != h.payloadHash)
    throw bad("corrupt (hash mismatch: the file changed after it was written)");
  if (expectedHash != 0 && h.payloadHash != expectedHash)
    throw bad(fmt::format("does not belong to this manifest (hash {}, the manifest says {})",
                          hashToHex(h.payloadHash), hashToHex(expectedHash)));
  return h;
}

class FileReader {
 public:
  FileReader(std::shared_ptr<const MappedFile> file, std::string path)
      : file_(std::move(file)), path_(std::move(path)), at_(kHeaderBytes) {}
  // The file's part format version (fields added later are read only from newer files).
  uint32_t version() const { return version_; }
  const std::string& path() const { return path_; }
  void setVersion(uint32_t version) { version_ = version; }
  // What keeps the mapping alive (for arrays read in place).
  std::shared_ptr<const void> keeper() const { return file_; }

  template <typename T>
  T pod() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T v;
    std::memcpy(&v, file_->data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  std::string str() {
    uint32_t n = pod<uint32_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(file_->data() + at_), n);
    at_ += n;
    return s;
  }
  template <typename T>
  std::vector<T> array() {
    static_assert(std::is_trivially_copyable_v<T>);
    uint64_t count = pod<uint64_t>();
    alignTo16();
    checkArray<T>(count);
    std::vector<T> v;
    if (count) {
      // One element of slack: Embree reads 16 bytes at the last vertex.
      v.reserve(count + 1);
      v.resize(count);
      std::memcpy(v.data(), file_->data() + at_, count * sizeof(T));
    }
    file_->release(at_, at_ + count * sizeof(T));
    at_ += count * sizeof(T);
    return v;
  }
  // The same array, not copied: the elements stay in the mapping, which the
  // returned array keeps alive (zero-copy loading of mesh and texel arrays).
  template <typename T>
  SharedArray<T> sharedArray() {
    const uint64_t count = pod<uint64_t>();
    alignTo16();
    checkArray<T>(count);
    const uint64_t end = at_ + count * sizeof(T);
    SharedArray<T> a = SharedArray<T>::shared(reinterpret_cast<const T*>(file_->data() + at_),
                                              count, file_, file_->size() - end >= sizeof(T));
    at_ = end;
    return a;
  }
  // A count of records that each take at least `minimumBytes`.
  uint64_t count(size_t minimumBytes) {
    uint64_t n = pod<uint64_t>();
    if (n > (file_->size() - at_) / std::max<size_t>(1, minimumBytes))
      fail("a count runs past the end");
    return n;
  }
  void end() {
    if (pod<uint32_t>() != kEndMarker || at_ != file_->size()) fail("the end marker is missing");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("{}: corrupt ({} at byte {})", path_, what, at_));
  }

 private:
  void need(uint64_t n) const {
    if (n > file_->size() - at_) fail("a record runs past the end");
  }
  void alignTo16() {
    if (at_ % 16) {
      need(16 - at_ % 16);
      at_ += 16 - at_ % 16;
    }
  }
  template <typename T>
  void checkArray(uint64_t count) const {
    static_assert(std::is_trivially_copyable_v<T>);
    if (count > (file_->size() - at_) / sizeof(T)) fail("an array runs past the end");
  }
  // Shared with the arrays read from it (sharedArray), which keep it mapped.
  std::shared_ptr<const MappedFile> file_;
  std::string path_;
  uint64_t at_;
  uint32_t version_ = kPartFormatVersion;
};

// A material's bump and normal maps and its mix (formats 5 on).
void readMapsAndMix(FileReader& r, Material& m) {
  m.bumpTexture = r.pod<int32_t>();
  m.bumpScale = r.pod<float>();
  m.normalTexture = r.pod<int32_t>();
  m.normalScale = r.pod<float>();
  m.mixedWith = r.pod<int32_t>();
  m.mixAmount = r.pod<float>();
}

// Formats 1 to 8 wrote the scattering parameters as Material's fields; they
// are read as the model the renderer then picked by them.
Material readMaterial(FileReader& r, size_t bsdfTables) {
  Material m;
  m.name = r.str();
  m.baseColor = r.pod<Vec3f>();
  m.baseColorTexture = r.pod<int32_t>();
  if (r.version() >= 9) {
    m.emission = r.pod<Vec3f>();
    m.alphaTexture = r.pod<int32_t>();
    m.alphaCutoff = r.pod<float>();
    const uint8_t sides = r.pod<uint8_t>();
    m.emitsBackSide = (sides & 1) != 0;
    m.lightSampledOnBackSide = (sides & 2) != 0;
    if (r.version() >= 12) {  // older: alpha below the cutoff cuts every ray
      const uint8_t test = (sides >> 2) & 3, rays = (sides >> 4) & 3;
      if (test > uint8_t(AlphaTest::Stochastic) || rays > uint8_t(AlphaRays::ShadowRaysOnly) ||
          sides >> 6)
        r.fail(fmt::format("material \"{}\": bad flags {:#x}", m.name, sides));
      m.alphaTest = AlphaTest(test);
      m.alphaRays = AlphaRays(rays);
    }
    readMapsAndMix(r, m);
    const std::string model = r.str();
    const std::vector<uint8_t> bytes = r.array<uint8_t>();
    const MaterialModelKind* kind = materialModelKind(model);
    if (!kind)
      throw InputError(
          fmt::format("{}: material \"{}\" has model \"{}\", which this Ferry does "
                      "not know (it knows {})",
                      r.path(), m.name, model, materialModelNames()));
    MaterialRecordReader record(
        bytes, fmt::format("{}: material \"{}\" ({})", r.path(), m.name, model), bsdfTables);
    m.model = kind->read(record);
    record.finish();
    return m;
  }
  // Formats 1 to 8.
  const float roughness = r.pod<float>(), metallic = r.pod<float>(), transmission = r.pod<float>(),
              ior = r.pod<float>();
  m.emission = r.pod<Vec3f>();
  m.alphaTexture = r.pod<int32_t>();
  m.alphaCutoff = r.pod<float>();
  if (r.version() >= 3) m.emitsBackSide = r.pod<uint8_t>() != 0;  // older: two-sided
  Vec3f specular{0};
  float specularRoughness = 0.3f, specularEta = 1.5f, sigma = 0;
  uint8_t coat = 0;        // additive, layered, FresnelBlend
  if (r.version() >= 4) {  // older: one lobe, no coat, Lambertian
    specular = r.pod<Vec3f>();
    specularRoughness = r.pod<float>();
    specularEta = r.pod<float>();
    coat = r.pod<uint8_t>();
    if (coat > 2)
      throw InputError(
          fmt::format("{}: material \"{}\" has an unknown coat model {}", r.path(), m.name, coat));
    sigma = r.pod<float>();
  }
  if (r.version() >= 5) readMapsAndMix(r, m);  // older: no bump or normal map, no mix
  int32_t table = kNoBsdfTable;
  if (r.version() >= 6) table = r.pod<int32_t>();  // older: no tables
  Vec3f transmittance{0};
  if (r.version() >= 7) transmittance = r.pod<Vec3f>();  // older: opaque
  if (table != kNoBsdfTable && (table < 0 || size_t(table) >= bsdfTables))
    r.fail(fmt::format("material \"{}\" names BSDF table {} of {}", m.name, table, bsdfTables));
  // The model the renderer picked from these fields.
  m.model = [&]() -> std::shared_ptr<const MaterialModel> {
    if (table != kNoBsdfTable) return std::make_shared<FourierModel>(table);
    if (transmission >= 0.5f) return std::make_shared<DielectricModel>(ior, roughness);
    if (metallic >= 0.5f && maxComponent(specular) > 0) {
      auto c = std::make_shared<CoatedConductorModel>();
      c->baseRoughness = roughness;
      c->specular = specular;
      c->roughness = specularRoughness;
      c->eta = specularEta;
      return c;
    }
    if (metallic >= 0.5f) return std::make_shared<ConductorModel>(roughness);
    if (maxComponent(transmittance) > 0)
      return std::make_shared<DiffuseTransmissionModel>(transmittance);
    if (maxComponent(specular) > 0 && coat == 2) {
      auto f = std::make_shared<FresnelBlendModel>();
      f->specular = specular;
      f->roughness = specularRoughness;
      return f;
    }
    if (maxComponent(specular) > 0) {
      auto c = std::make_shared<CoatedDiffuseModel>();
      c->specular = specular;
      c->roughness = specularRoughness;
      c->eta = specularEta;
      c->layered = coat == 1;
      c->sigmaDegrees = sigma;
      return c;
    }
    return std::make_shared<DiffuseModel>(sigma);
  }();
  return m;
}

std::shared_ptr<const FourierBsdfTable> readBsdfTable(FileReader& r) {
  auto t = std::make_shared<FourierBsdfTable>();
  t->name = r.str();
  t->nMu = r.pod<int32_t>();
  t->nChannels = r.pod<int32_t>();
  t->mMax = r.pod<int32_t>();
  t->eta = r.pod<float>();
  t->mu = r.array<float>();
  t->cdf = r.array<float>();
  t->offset = r.array<uint32_t>();
  t->order = r.array<int32_t>();
  t->coefficients = r.array<float>();
  // The same checks as reading the .bsdf file: sizes, series in range.
  if (std::string what = t->finish(); !what.empty())
    r.fail(fmt::format("BSDF table \"{}\": {}", t->name, what));
  return t;
}

// A combined texture's parts nest at most this deep.
constexpr int kMaxTextureDepth = 32;

Texture readTexture(FileReader& r, int depth = 0) {
  if (depth > kMaxTextureDepth) r.fail("textures nested too deeply");
  Texture t;
  t.name = r.str();
  t.width = r.pod<int32_t>();
  t.height = r.pod<int32_t>();
  uint8_t wrap = r.pod<uint8_t>();
  if (wrap > uint8_t(WrapMode::Mirror)) r.fail("bad wrap mode");
  t.wrap = WrapMode(wrap);
  t.srgb = r.pod<uint8_t>() != 0;
  t.rgba = r.sharedArray<uint8_t>();
  if (t.width < 0 || t.height < 0 || t.rgba.size() != t.texelCount() * 4)
    r.fail("texture size mismatch");
  if (r.version() >= 5) {  // older: images only
    const uint8_t kind = r.pod<uint8_t>();
    if (kind > uint8_t(SolidTextureKind::Windy)) r.fail("bad solid texture kind");
    t.solid.kind = SolidTextureKind(kind);
    t.solid.worldToTexture = r.pod<Affine3f>();
    t.solid.octaves = r.pod<int32_t>();
    if (t.solid.octaves < 0 || t.solid.octaves > 32) r.fail("bad solid texture octaves");
    t.solid.omega = r.pod<float>();
    t.solid.scale = r.pod<float>();
    t.solid.variation = r.pod<float>();
  }
  if (r.version() >= 11) {  // older: no combinations
    const uint8_t combination = r.pod<uint8_t>();
    if (combination > uint8_t(TextureCombination::Bilerp)) r.fail("bad texture combination");
    t.combination = TextureCombination(combination);
    t.mapping = r.pod<Vec4f>();
    for (TextureOperand& o : t.operands) {
      o.constant = r.pod<Vec3f>();
      o.part = r.pod<int32_t>();
      if (!isFinite(o.constant)) r.fail("non-finite texture constant");
    }
    const uint32_t parts = r.pod<uint32_t>();
    if (parts > t.operands.size()) r.fail("too many texture parts");
    for (uint32_t i = 0; i < parts; ++i) t.parts.push_back(readTexture(r, depth + 1));
    for (const TextureOperand& o : t.operands)
      if (o.part < -1 || o.part >= int32_t(parts)) r.fail("texture operand out of range");
  }
  return t;
}

Mesh readMesh(FileReader& r) {
  Mesh m;
  m.name = r.str();
  m.material = r.pod<int32_t>();
  m.positions = r.sharedArray<Vec3f>();
  m.normals = r.sharedArray<Vec3f>();
  m.uvs = r.sharedArray<Vec2f>();
  m.indices = r.sharedArray<Vec3i>();
  return m;
}

// A geometry of another kind: its name, material, kind by name and the
// kind's record (scene/shape.h, shapes/shape_kinds.h).
Geometry readGeometry(FileReader& r) {
  Geometry g;
  g.name = r.str();
  g.material = r.pod<int32_t>();
  const std::string kind = r.str();
  // In place: a shape may keep its arrays in the mapping (volume bricks' samples).
  const SharedArray<uint8_t> bytes = r.sharedArray<uint8_t>();
  const ShapeKind* k = shapeKind(kind);
  if (!k)
    throw InputError(
        fmt::format("{}: geometry \"{}\" is of kind \"{}\", which this Ferry does "
                    "not know (it knows {})",
                    r.path(), g.name, kind, shapeKindNames()));
  RecordReader record(std::span<const uint8_t>(bytes.data(), bytes.size()),
                      fmt::format("{}: geometry \"{}\" ({})", r.path(), g.name, kind), r.keeper());
  g.shape = k->read(record);
  record.finish();
  return g;
}

// Reads what writeContent wrote; checks every index (Scene::validate).
void readContent(FileReader& r, Scene& scene, std::vector<RankSet>& owners, size_t ownerWords) {
  for (uint64_t n = r.count(8); n > 0; --n) scene.textures.push_back(readTexture(r));
  if (r.version() >= 6)
    for (uint64_t n = r.count(8); n > 0; --n) scene.bsdfTables.push_back(readBsdfTable(r));
  for (uint64_t n = r.count(8); n > 0; --n)
    scene.materials.push_back(readMaterial(r, scene.bsdfTables.size()));
  for (uint64_t n = r.count(8); n > 0; --n) scene.meshes.push_back(readMesh(r));
  if (r.version() >= 9)  // older: triangle meshes only
    for (uint64_t n = r.count(8); n > 0; --n) scene.geometries.push_back(readGeometry(r));
  for (uint64_t n = r.count(8); n > 0; --n) {
    Object o;
    o.name = r.str();
    o.meshes = r.array<int32_t>();
    if (r.version() >= 9) o.geometries = r.array<int32_t>();
    scene.objects.push_back(std::move(o));
  }
  std::vector<int32_t> objects = r.array<int32_t>();
  std::vector<Affine3f> transforms = r.array<Affine3f>();
  std::vector<uint64_t> words = r.array<uint64_t>();
  if (transforms.size() != objects.size() || words.size() != objects.size() * ownerWords)
    r.fail("instance arrays differ in size");
  owners.clear();
  for (size_t i = 0; i < objects.size(); ++i)
    owners.push_back(RankSet::fromWords(words.data() + i * ownerWords, ownerWords));
  scene.instances.resize(objects.size());
  for (size_t i = 0; i < objects.size(); ++i) scene.instances[i] = {objects[i], transforms[i]};
  if (r.version() >= 14) {  // older: nothing moves
    const std::vector<uint32_t> keyCounts = r.array<uint32_t>();
    const std::vector<MotionKey> keys = r.array<MotionKey>();
    if (keyCounts.size() != objects.size()) r.fail("instance arrays differ in size");
    size_t next = 0;
    for (size_t i = 0; i < objects.size(); ++i) {
      const uint32_t n = keyCounts[i];
      if (n == 0) continue;
      if (n < 2 || n > keys.size() - next) r.fail("bad motion key counts");
      scene.instances[i].motion = std::make_shared<const InstanceMotion>(
          std::vector<MotionKey>(keys.begin() + long(next), keys.begin() + long(next + n)));
      next += n;
    }
    if (next != keys.size()) r.fail("more motion keys than moving instances");
  }
}

void readLights(FileReader& r, Scene& lights) {
  std::vector<RankSet> unused;
  readContent(r, lights, unused, 1);
  for (uint64_t n = r.count(28); n > 0; --n) {
    SunLight s;
    s.direction = r.pod<Vec3f>();
    s.irradiance = r.pod<Vec3f>();
    s.angularRadius = r.pod<float>();
    lights.suns.push_back(s);
  }
  lights.environment.color = r.pod<Vec3f>();
  lights.environment.rotation = r.pod<float>();
  if (r.pod<uint8_t>()) {
    auto image = std::make_shared<HdrImage>();
    image->name = r.str();
    image->width = r.pod<int32_t>();
    image->height = r.pod<int32_t>();
    image->pixels = r.array<Vec3f>();
    if (image->width < 0 || image->height < 0 ||
        image->pixels.size() != size_t(image->width) * size_t(image->height))
      r.fail("environment image size mismatch");
    lights.environment.image = std::move(image);
  }
  if (r.version() < 13) return;  // older: point and spot lights were emissive meshes
  for (uint64_t n = r.count(45); n > 0; --n) {
    PointLight l;
    l.position = r.pod<Vec3f>();
    l.intensity = r.pod<Vec3f>();
    l.direction = r.pod<Vec3f>();
    l.cosTotalWidth = r.pod<float>();
    l.cosFalloffStart = r.pod<float>();
    const uint8_t falloff = r.pod<uint8_t>();
    if (falloff > uint8_t(PointLight::Falloff::SmoothStep))
      r.fail(fmt::format("point light falloff {} is not 0, 1 or 2", falloff));
    l.falloff = PointLight::Falloff(falloff);
    if (!isFinite(l.position) || !isFinite(l.intensity) || !isFinite(l.direction))
      r.fail("a point light is not finite");
    lights.pointLights.push_back(l);
  }
}

template <typename Fill>
void validated(const std::string& path, Scene& scene, Fill&& fill) {
  fill();
  try {
    scene.validate();
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: corrupt ({})", path, e.what()));
  }
}

}  // namespace

WrittenFile writePartFile(const std::string& path, const Scene& scene,
                          const std::vector<int32_t>& instances, const std::vector<RankSet>& owners,
                          int rank, int ranks) {
  FERRY_CHECK_EQ(owners.size(), scene.instances.size());
  FERRY_CHECK(std::is_sorted(instances.begin(), instances.end()));
  // The media inside subsurface materials go (their models keep the
  // coefficients the probes need; walks need the scene file); others are
  // refused.
  if (std::any_of(scene.media.begin(), scene.media.end(),
                  [](const Medium& m) { return !m.subsurface; }))
    throw InputError(
        fmt::format("{}: scene '{}' has participating media, which part files do "
                    "not store yet: render the scene file itself",
                    path, scene.name));
  WrittenFile written;
  writeFileAtomically(path, [&](const std::string& tmp) {
    FileWriter w(tmp);
    w.pod(uint32_t(rank));
    w.pod(uint32_t(ranks));
    w.str(scene.name);
    writeContent(w, scene, instances, &owners, rankSetWords(ranks));
    written = w.finish(kKindPart, uint32_t(rank), uint32_t(ranks));
  });
  return written;
}

LoadedPart readPartFile(const std::string& path, uint64_t expectedHash) {
  auto file = std::make_shared<const MappedFile>(path);
  Header h = checkFile(*file, path, kKindPart, expectedHash);
  FileReader r(file, path);
  r.setVersion(h.version);
  LoadedPart part;
  part.rank = int(r.pod<uint32_t>());
  part.ranks = int(r.pod<uint32_t>());
  if (uint32_t(part.rank) != h.rank || uint32_t(part.ranks) != h.ranks || part.rank >= part.ranks)
    r.fail("rank fields disagree");
  validated(path, part.scene, [&] {
    part.scene.name = r.str();
    if (h.version == 1 && part.ranks > 64) r.fail("format 1 holds at most 64 ranks");
    readContent(r, part.scene, part.owners, h.version == 1 ? 1 : rankSetWords(part.ranks));
    r.end();
  });
  const RankSet all = RankSet::firstN(part.ranks);
  for (const RankSet& m : part.owners) {
    if (!m.contains(part.rank)) r.fail("an instance is not owned by the part's own rank");
    if (!m.isSubsetOf(all)) r.fail("an instance has owners outside the part directory's ranks");
  }
  return part;
}

WrittenFile writeSharedFile(const std::string& path, const SharedData& shared) {
  WrittenFile written;
  writeFileAtomically(path, [&](const std::string& tmp) {
    FileWriter w(tmp);
    w.pod(uint32_t(shared.ranks));
    w.pod(uint64_t(shared.views.size()));
    for (const CameraView& v : shared.views) {
      w.str(v.name);
      w.pod(v.from);
      w.pod(v.at);
      w.pod(v.up);
      w.pod(v.fovY);
      w.pod(uint8_t(v.leftHanded));
      w.pod(v.lensRadius);
      w.pod(v.focalDistance);
      // Format 14: a moving camera's keys (none when it stays put).
      w.array(v.motion ? v.motion->keys() : std::vector<MotionKey>());
    }
    w.pod(uint8_t(shared.filmWidth.has_value()));
    w.pod(int32_t(shared.filmWidth.value_or(0)));
    w.pod(uint8_t(shared.filmHeight.has_value()));
    w.pod(int32_t(shared.filmHeight.value_or(0)));
    w.str(shared.filmFilename);
    writeLights(w, shared.lights);
    std::vector<Box3f> boxes;
    std::vector<uint64_t> owners;
    const size_t words = rankSetWords(shared.ranks);
    for (const Proxy& p : shared.proxies) {
      boxes.push_back(p.bounds);
      for (size_t k = 0; k < words; ++k) owners.push_back(p.owners.word(k));
    }
    w.array(boxes);
    w.array(owners);
    // Instanced proxies (format 8): per proxy its shape (-1: a box), the
    // instanced ones' transforms in order, and the shapes' boxes.
    std::vector<int32_t> shapeOf;
    std::vector<Affine3f> toWorld;
    for (const Proxy& p : shared.proxies) {
      shapeOf.push_back(p.shape);
      if (p.shape >= 0) toWorld.push_back(shared.proxyPlacements[size_t(p.placement)]);
    }
    std::vector<uint64_t> shapeEnds;
    std::vector<Box3f> shapeBoxes;
    for (const ProxyShape& s : shared.proxyShapes) {
      shapeBoxes.insert(shapeBoxes.end(), s.boxes.begin(), s.boxes.end());
      shapeEnds.push_back(shapeBoxes.size());
    }
    w.array(shapeOf);
    w.array(toWorld);
    w.array(shapeEnds);
    w.array(shapeBoxes);
    written = w.finish(kKindShared, 0xffffffffu, uint32_t(shared.ranks));
  });
  return written;
}

namespace {
// Format 8's instanced proxies, checked: every shape index names a shape,
// one transform per instanced proxy, shape ends increasing up to the boxes.
void readInstancedProxies(FileReader& r, SharedData& shared) {
  const std::vector<int32_t> shapeOf = r.array<int32_t>();
  std::vector<Affine3f> toWorld = r.array<Affine3f>();
  const std::vector<uint64_t> shapeEnds = r.array<uint64_t>();
  const std::vector<Box3f> shapeBoxes = r.array<Box3f>();
  if (shapeOf.size() != shared.proxies.size()) r.fail("proxy shape array differs in size");
  uint64_t begin = 0;
  for (uint64_t end : shapeEnds) {
    if (end < begin || end > shapeBoxes.size()) r.fail("proxy shape ends out of order");
    shared.proxyShapes.push_back(
        {{shapeBoxes.begin() + ptrdiff_t(begin), shapeBoxes.begin() + ptrdiff_t(end)}});
    begin = end;
  }
  size_t next = 0;
  for (size_t k = 0; k < shapeOf.size(); ++k) {
    if (shapeOf[k] < 0) continue;
    if (size_t(shapeOf[k]) >= shared.proxyShapes.size()) r.fail("proxy shape out of range");
    if (next >= toWorld.size()) r.fail("fewer proxy transforms than instanced proxies");
    shared.proxies[k].shape = shapeOf[k];
    shared.proxies[k].placement = int32_t(next++);
  }
  if (next != toWorld.size()) r.fail("more proxy transforms than instanced proxies");
  shared.proxyPlacements = std::move(toWorld);
}
}  // namespace

SharedData readSharedFile(const std::string& path, uint64_t expectedHash) {
  auto file = std::make_shared<const MappedFile>(path);
  const Header h = checkFile(*file, path, kKindShared, expectedHash);
  FileReader r(file, path);
  r.setVersion(h.version);
  SharedData shared;
  shared.ranks = int(r.pod<uint32_t>());
  for (uint64_t n = r.count(45); n > 0; --n) {
    CameraView v;
    v.name = r.str();
    v.from = r.pod<Vec3f>();
    v.at = r.pod<Vec3f>();
    v.up = r.pod<Vec3f>();
    v.fovY = r.pod<float>();
    v.leftHanded = r.pod<uint8_t>() != 0;
    if (r.version() >= 10) {  // older: pinholes
      v.lensRadius = r.pod<float>();
      v.focalDistance = r.pod<float>();
    }
    if (r.version() >= 14) {  // older: still cameras
      std::vector<MotionKey> keys = r.array<MotionKey>();
      if (keys.size() == 1) r.fail("bad camera motion key count");
      if (!keys.empty()) v.motion = std::make_shared<const InstanceMotion>(std::move(keys));
    }
    shared.views.push_back(std::move(v));
  }
  const bool hasWidth = r.pod<uint8_t>() != 0;
  const int32_t width = r.pod<int32_t>();
  const bool hasHeight = r.pod<uint8_t>() != 0;
  const int32_t height = r.pod<int32_t>();
  if (hasWidth) shared.filmWidth = width;
  if (hasHeight) shared.filmHeight = height;
  shared.filmFilename = r.str();
  validated(path, shared.lights, [&] {
    readLights(r, shared.lights);
    if (h.version == 1) {
      for (const ProxyV1& p : r.array<ProxyV1>())
        shared.proxies.push_back({p.bounds, RankSet::fromMask(p.owners)});
    } else {
      const size_t words = rankSetWords(shared.ranks);
      std::vector<Box3f> boxes = r.array<Box3f>();
      std::vector<uint64_t> owners = r.array<uint64_t>();
      if (owners.size() != boxes.size() * words) r.fail("proxy arrays differ in size");
      shared.proxies.reserve(boxes.size());
      for (size_t k = 0; k < boxes.size(); ++k)
        shared.proxies.push_back({boxes[k], RankSet::fromWords(owners.data() + k * words, words)});
    }
    if (h.version >= 8) readInstancedProxies(r, shared);
    r.end();
  });
  return shared;
}

}  // namespace ferry
