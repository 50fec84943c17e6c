#include "io/checkpoints/checkpoint_file.h"

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include "core/error.h"
#include "core/hash64.h"
#include "io/images/image_io.h"

namespace ferry {
namespace {

constexpr char kMagic[8] = {'F', 'E', 'R', 'R', 'Y', 'C', 'K', 'P'};
constexpr uint32_t kVersion = 1;
constexpr uint32_t kFractionBits = 28;  // FrameBuffer::kFractionBits (checked where it is used)
constexpr size_t kMaxDescription = 1 << 16;
constexpr int kMaxSide = 1 << 16;

template <typename T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// Reads fields from the file's bytes, failing with the file's name.
class Reader {
 public:
  Reader(const std::string& path, const std::string& bytes) : path_(path), bytes_(bytes) {}
  template <typename T>
  T get(const char* what) {
    T value;
    need(sizeof(T), what);
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  void need(size_t n, const char* what) const {
    if (bytes_.size() - at_ < n)
      throw InputError(fmt::format("{}: truncated checkpoint (ends in its {})", path_, what));
  }
  size_t at() const { return at_; }
  void skip(size_t n) { at_ += n; }
  const char* here() const { return bytes_.data() + at_; }

 private:
  const std::string& path_;
  const std::string& bytes_;
  size_t at_ = 0;
};

}  // namespace

void writeCheckpoint(const std::string& path, const Checkpoint& c) {
  FERRY_CHECK_EQ(c.sums.size(), size_t(c.width) * size_t(c.height) * 3);
  std::string out;
  out.reserve(64 + c.description.size() + c.sums.size() * sizeof(int64_t));
  out.append(kMagic, sizeof(kMagic));
  put(out, kVersion);
  put(out, kFractionBits);
  put(out, c.identity);
  put(out, int32_t(c.width));
  put(out, int32_t(c.height));
  put(out, int32_t(c.frames));
  put(out, int32_t(c.samplesPerPixel));
  put(out, uint32_t(c.description.size()));
  out += c.description;
  out.append(reinterpret_cast<const char*>(c.sums.data()), c.sums.size() * sizeof(int64_t));
  put(out, hash64(out.data(), out.size()));
  writeFileAtomically(path, [&](const std::string& temp) {
    std::ofstream file(temp, std::ios::binary);
    file.write(out.data(), std::streamsize(out.size()));
    file.close();
    if (!file) throw InputError(fmt::format("{}: could not write the checkpoint", path));
  });
}

Checkpoint readCheckpoint(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(fmt::format("{}: no such checkpoint (cannot open it)", path));
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  Reader r(path, bytes);
  r.need(sizeof(kMagic), "header");
  if (std::memcmp(r.here(), kMagic, sizeof(kMagic)) != 0)
    throw InputError(fmt::format("{}: not a Ferry checkpoint", path));
  r.skip(sizeof(kMagic));
  const uint32_t version = r.get<uint32_t>("version");
  if (version != kVersion)
    throw InputError(fmt::format("{}: checkpoint version {}, this Ferry reads version {}", path,
                                 version, kVersion));
  const uint32_t fractionBits = r.get<uint32_t>("header");
  if (fractionBits != kFractionBits)
    throw InputError(fmt::format("{}: fixed point with {} fraction bits, this Ferry uses {}", path,
                                 fractionBits, kFractionBits));
  Checkpoint c;
  c.identity = r.get<uint64_t>("header");
  c.width = r.get<int32_t>("header");
  c.height = r.get<int32_t>("header");
  c.frames = r.get<int32_t>("header");
  c.samplesPerPixel = r.get<int32_t>("header");
  if (c.width < 1 || c.height < 1 || c.width > kMaxSide || c.height > kMaxSide || c.frames < 1 ||
      c.samplesPerPixel < 1)
    throw InputError(fmt::format("{}: bad checkpoint header ({}x{}, {} frames of {} spp)", path,
                                 c.width, c.height, c.frames, c.samplesPerPixel));
  const uint32_t descriptionBytes = r.get<uint32_t>("header");
  if (descriptionBytes > kMaxDescription)
    throw InputError(
        fmt::format("{}: bad checkpoint header (description of {} bytes)", path, descriptionBytes));
  r.need(descriptionBytes, "description");
  c.description.assign(r.here(), descriptionBytes);
  r.skip(descriptionBytes);
  const size_t values = size_t(c.width) * size_t(c.height) * 3;
  // The size must match exactly before anything large is allocated.
  const size_t expected = r.at() + values * sizeof(int64_t) + sizeof(uint64_t);
  if (bytes.size() != expected)
    throw InputError(fmt::format("{}: {} bytes, a {}x{} checkpoint has {}{}", path, bytes.size(),
                                 c.width, c.height, expected,
                                 bytes.size() < expected ? " (truncated)" : ""));
  c.sums.resize(values);
  std::memcpy(c.sums.data(), r.here(), values * sizeof(int64_t));
  r.skip(values * sizeof(int64_t));
  const uint64_t stored = r.get<uint64_t>("hash");
  if (hash64(bytes.data(), bytes.size() - sizeof(uint64_t)) != stored)
    throw InputError(fmt::format("{}: corrupt checkpoint (its hash does not match)", path));
  return c;
}

}  // namespace ferry
