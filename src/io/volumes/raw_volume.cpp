#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include "core/error.h"
#include "io/volumes/volume_files.h"

namespace ferry {
namespace {

constexpr std::string_view kPrefix = "raw:";
constexpr const char* kKeys = "dims, format, spacing, origin, tf, opacity";

// "A,B,C" as three numbers.
template <typename T>
bool parseTriple(std::string_view text, T out[3]) {
  for (int i = 0; i < 3; ++i) {
    const size_t comma = text.find(',');
    if ((i < 2) != (comma != std::string_view::npos)) return false;
    const std::string_view part = text.substr(0, comma);
    const char* end = part.data() + part.size();
    auto [ptr, ec] = std::from_chars(part.data(), end, out[i]);
    if (part.empty() || ec != std::errc() || ptr != end) return false;
    if (i < 2) text = text.substr(comma + 1);
  }
  return true;
}

}  // namespace

size_t rawSampleBytes(const std::string& format) {
  return format == "uint8" ? 1 : format == "uint16" ? 2 : format == "float32" ? 4 : 0;
}

bool isRawVolumeSpec(const std::string& spec) {
  return std::string_view(spec).starts_with(kPrefix);
}

Scene loadRawVolume(const std::string& spec) {
  std::string_view rest = std::string_view(spec).substr(kPrefix.size());
  const size_t question = rest.find('?');
  const std::string path(rest.substr(0, question));
  auto fail = [&](const std::string& what) { throw InputError(fmt::format("{}: {}", spec, what)); };
  if (path.empty()) fail("no file (raw:PATH?dims=X,Y,Z&format=uint8|uint16|float32)");
  uint64_t dims[3] = {0, 0, 0};
  float spacing[3] = {1, 1, 1}, origin[3] = {0, 0, 0};
  std::string format, tfPath;
  std::optional<float> opacity;
  bool haveDims = false;
  std::string_view query = question == std::string_view::npos ? "" : rest.substr(question + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view item = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    if (item.empty()) continue;
    const size_t eq = item.find('=');
    if (eq == std::string_view::npos)
      fail(fmt::format("'{}' needs a value (keys: {})", item, kKeys));
    const std::string_view key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "dims") {
      if (!parseTriple(value, dims) || dims[0] == 0 || dims[1] == 0 || dims[2] == 0)
        fail(fmt::format("dims '{}': expected three positive integers X,Y,Z", value));
      haveDims = true;
    } else if (key == "format") {
      format = std::string(value);
    } else if (key == "spacing") {
      if (!parseTriple(value, spacing) || !(std::min({spacing[0], spacing[1], spacing[2]}) > 0) ||
          !std::isfinite(spacing[0] + spacing[1] + spacing[2]))
        fail(fmt::format("spacing '{}': expected three positive numbers", value));
    } else if (key == "origin") {
      if (!parseTriple(value, origin) || !std::isfinite(origin[0] + origin[1] + origin[2]))
        fail(fmt::format("origin '{}': expected three numbers", value));
    } else if (key == "tf") {
      tfPath = std::string(value);
    } else if (key == "opacity") {
      float s = 0;
      auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), s);
      if (value.empty() || ec != std::errc() || ptr != value.data() + value.size() || !(s >= 0) ||
          !std::isfinite(s))
        fail(fmt::format("opacity '{}': expected a number 0 or more", value));
      opacity = s;
    } else {
      fail(fmt::format("unknown key '{}' (keys: {})", key, kKeys));
    }
  }
  if (!haveDims) fail("no dims (dims=X,Y,Z)");
  const size_t bytesPerSample = rawSampleBytes(format);
  if (bytesPerSample == 0)
    fail(fmt::format("format '{}': expected uint8, uint16 or float32", format));
  constexpr uint64_t kMaxSide = uint64_t(std::numeric_limits<int32_t>::max());
  if (dims[0] > kMaxSide || dims[1] > kMaxSide || dims[2] > kMaxSide ||
      dims[0] * dims[1] > (uint64_t(1) << 62) / dims[2] / bytesPerSample)
    fail(fmt::format("dims {}x{}x{} overflow", dims[0], dims[1], dims[2]));
  const uint64_t samples = dims[0] * dims[1] * dims[2];
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(fmt::format("{}: cannot read ({})", path, ec.message()));
  if (size != samples * bytesPerSample)
    throw InputError(fmt::format("{}: {} bytes, but dims {}x{}x{} of {} need {}", path, size,
                                 dims[0], dims[1], dims[2], format, samples * bytesPerSample));
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes(size);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
    throw InputError(fmt::format("{}: read failed", path));

  std::vector<float> values(samples);
  if (format == "uint8") {
    for (uint64_t i = 0; i < samples; ++i) values[i] = float(bytes[i]) / 255.0f;
  } else if (format == "uint16") {
    for (uint64_t i = 0; i < samples; ++i)
      values[i] = float(uint16_t(bytes[2 * i] | (bytes[2 * i + 1] << 8))) / 65535.0f;
  } else {
    float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
    for (uint64_t i = 0; i < samples; ++i) {
      uint32_t bits = uint32_t(bytes[4 * i]) | uint32_t(bytes[4 * i + 1]) << 8 |
                      uint32_t(bytes[4 * i + 2]) << 16 | uint32_t(bytes[4 * i + 3]) << 24;
      float v;
      std::memcpy(&v, &bits, 4);
      if (!std::isfinite(v))
        throw InputError(fmt::format("{}: sample {} (x {}, y {}, z {}) is {}", path, i, i % dims[0],
                                     (i / dims[0]) % dims[1], i / (dims[0] * dims[1]), v));
      values[i] = v;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    // In double: the range of two finite floats can overflow a float.
    const double range = double(hi) - double(lo);
    for (float& v : values) v = range > 0 ? float((double(v) - double(lo)) / range) : 0.0f;
  }
  TransferFunction tf =
      tfPath.empty() ? TransferFunction::standard() : readTransferFunction(tfPath);
  const Box3f box{{origin[0], origin[1], origin[2]},
                  {origin[0] + float(dims[0]) * spacing[0], origin[1] + float(dims[1]) * spacing[1],
                   origin[2] + float(dims[2]) * spacing[2]}};
  // The scale counts mean free paths across the box's longest side at
  // opacity 1, so that a volume looks the same whatever its units.
  tf = tf.withScale(opacity.value_or(tf.scale()) / maxComponent(box.size()));
  const std::string name = std::filesystem::path(path).filename().string();
  auto grid =
      std::make_shared<DensityGrid>(int(dims[0]), int(dims[1]), int(dims[2]), std::move(values));
  return volumeScene(
      name,
      transferFunctionMedium(name, std::move(grid), std::make_shared<TransferFunction>(tf), box),
      box);
}

}  // namespace ferry
