#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string_view>

#include "core/error.h"
#include "io/byte_stream.h"
#include "io/json_numbers.h"
#include "io/text_file.h"
#include "io/volumes/volume_files.h"
#include "shapes/volume_brick.h"

namespace ferry {
namespace {

static_assert(std::endian::native == std::endian::little, "brick files are little-endian");
constexpr std::string_view kPrefix = "bricks:";

using Json = nlohmann::json;

// `count` floats of `path`, mapped (read only, kept as long as the array is).
SharedArray<float> mappedFloats(const std::string& path, uint64_t count) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) throw InputError(fmt::format("{}: cannot open ({})", path, std::strerror(errno)));
  const size_t bytes = size_t(count) * sizeof(float);
  void* at = ::mmap(nullptr, bytes, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  if (at == MAP_FAILED)
    throw InputError(fmt::format("{}: cannot map ({})", path, std::strerror(errno)));
  std::shared_ptr<const void> keeper(
      at, [bytes](const void* p) { ::munmap(const_cast<void*>(p), bytes); });
  return SharedArray<float>::shared(static_cast<const float*>(at), size_t(count), std::move(keeper),
                                    false);
}

struct BrickEntry {
  std::string file;
  std::array<int, 3> lo{}, hi{};
  int rank = -1;
};

}  // namespace

bool isBrickManifestSpec(const std::string& spec) {
  return std::string_view(spec).starts_with(kPrefix);
}

Scene loadBrickPiece(const std::string& spec, int rank, int ranks, const VolumeLook& look) {
  const std::string path(std::string_view(spec).substr(kPrefix.size()));
  auto fail = [&](const std::string& what) { throw InputError(fmt::format("{}: {}", path, what)); };
  const std::string text = readTextFile(path, "the brick manifest");
  Json j;
  try {
    j = Json::parse(text);
  } catch (const Json::exception& e) {
    fail(fmt::format("not JSON ({})", e.what()));
  }
  if (!j.is_object()) fail("expected an object with dims, format and bricks");
  auto triple = [&](const char* key, auto fallback) {
    using T = typename decltype(fallback)::value_type;
    if (!j.contains(key)) return fallback;
    const Json& v = j[key];
    decltype(fallback) out;
    if (!v.is_array() || v.size() != 3) fail(fmt::format("{}: expected three numbers", key));
    for (int a = 0; a < 3; ++a) {
      const std::optional<T> n = numberAs<T>(v[a]);
      if (!n) fail(fmt::format("{}: expected three numbers that fit", key));
      out[a] = *n;
    }
    return out;
  };
  try {
    if (!j.contains("dims")) fail("no dims ([X, Y, Z] samples of the whole volume)");
    const std::array<int64_t, 3> dims = triple("dims", std::array<int64_t, 3>{});
    for (int64_t n : dims)
      if (n < 1 || n > std::numeric_limits<int32_t>::max())
        fail(fmt::format("dims: {} is not a positive 32-bit count", n));
    const std::array<float, 3> spacing = triple("spacing", std::array<float, 3>{1, 1, 1});
    const std::array<float, 3> origin = triple("origin", std::array<float, 3>{0, 0, 0});
    for (int a = 0; a < 3; ++a) {
      if (!(spacing[a] > 0) || !std::isfinite(spacing[a]))
        fail("spacing: expected three positive numbers");
      if (!std::isfinite(origin[a])) fail("origin: expected three numbers");
    }
    const std::string format = j.value("format", std::string());
    const size_t bytesPerSample = rawSampleBytes(format);
    if (bytesPerSample == 0)
      fail(fmt::format("format '{}': expected uint8, uint16 or float32", format));
    float rangeLo = 0, rangeHi = 1;
    if (format == "float32") {
      if (!j.contains("range")) fail("a float32 volume needs its whole range ([LO, HI])");
      const Json& r = j["range"];
      if (!r.is_array() || r.size() != 2) fail("range: expected [LO, HI]");
      const std::optional<float> lo = numberAs<float>(r[0]), hi = numberAs<float>(r[1]);
      if (!lo || !hi || !(*hi >= *lo)) fail("range: expected finite LO <= HI");
      if (!std::isfinite(*hi - *lo)) fail("range: HI - LO is more than a float holds");
      rangeLo = *lo;
      rangeHi = *hi;
    }
    if (!j.contains("bricks") || !j["bricks"].is_array() || j["bricks"].empty())
      fail("no bricks (a list of {file, lo, hi})");
    const std::filesystem::path dir = std::filesystem::path(path).parent_path();
    std::vector<BrickEntry> bricks;
    uint64_t covered = 0;
    for (size_t b = 0; b < j["bricks"].size(); ++b) {
      const Json& e = j["bricks"][b];
      auto brickFail = [&](const std::string& what) { fail(fmt::format("brick {}: {}", b, what)); };
      if (!e.is_object() || !e.contains("file") || !e["file"].is_string())
        brickFail("expected {file, lo, hi}");
      BrickEntry entry;
      entry.file = (dir / e["file"].get<std::string>()).string();
      for (const char* key : {"lo", "hi"}) {
        if (!e.contains(key) || !e[key].is_array() || e[key].size() != 3)
          brickFail(fmt::format("{}: expected three cell indices", key));
        for (int a = 0; a < 3; ++a) {
          if (!e[key][a].is_number_integer())
            brickFail(fmt::format("{}: expected three cell indices", key));
          const int64_t v = e[key][a].get<int64_t>();
          if (v < 0 || v > dims[a]) brickFail(fmt::format("{} is outside the grid", key));
          (key[0] == 'l' ? entry.lo : entry.hi)[a] = int(v);
        }
      }
      for (int a = 0; a < 3; ++a)
        if (entry.lo[a] >= entry.hi[a]) brickFail("lo must be below hi along every axis");
      entry.rank = int(b % size_t(ranks));
      if (e.contains("rank")) {
        if (!e["rank"].is_number_integer() || e["rank"].get<int64_t>() < 0)
          brickFail("rank: expected a rank number");
        const int64_t r = e["rank"].get<int64_t>();
        if (rank >= 0 && r >= ranks)
          brickFail(fmt::format("rank {}: the job has {} ranks", r, ranks));
        entry.rank = int(r);
      }
      covered += uint64_t(entry.hi[0] - entry.lo[0]) * uint64_t(entry.hi[1] - entry.lo[1]) *
                 uint64_t(entry.hi[2] - entry.lo[2]);
      bricks.push_back(std::move(entry));
    }
    for (size_t a = 0; a < bricks.size(); ++a)
      for (size_t b = a + 1; b < bricks.size(); ++b) {
        bool overlap = true;
        for (int k = 0; k < 3; ++k)
          overlap =
              overlap && bricks[a].lo[k] < bricks[b].hi[k] && bricks[b].lo[k] < bricks[a].hi[k];
        if (overlap) fail(fmt::format("bricks {} and {} overlap", a, b));
      }
    const uint64_t cells = uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]);
    if (covered != cells) fail(fmt::format("the bricks cover {} of the {} cells", covered, cells));

    const Box3f box{
        {origin[0], origin[1], origin[2]},
        {origin[0] + float(dims[0]) * spacing[0], origin[1] + float(dims[1]) * spacing[1],
         origin[2] + float(dims[2]) * spacing[2]}};
    TransferFunction tf = TransferFunction::standard();
    if (j.contains("tf")) {
      if (!j["tf"].is_string()) fail("tf: expected a file name");
      tf = readTransferFunction((dir / j["tf"].get<std::string>()).string());
    }
    float opacity = tf.scale();
    if (j.contains("opacity")) {
      const std::optional<float> o = numberAs<float>(j["opacity"]);
      if (!o || !(*o >= 0)) fail("opacity: expected a number 0 or more");
      opacity = *o;
    }
    // As a raw: volume: mean free paths across the box's longest side at opacity 1.
    tf = tf.withScale(opacity / maxComponent(box.size()));
    if (!look.isDefault()) tf = restyled(tf, look);
    auto volume = std::make_shared<VolumeBrick::Volume>();
    volume->dims = {int(dims[0]), int(dims[1]), int(dims[2])};
    volume->gridFromWorld = unitFromBox(box);
    volume->transfer = std::make_shared<const TransferFunction>(std::move(tf));
    if (format == "float32") {
      volume->normalise = true;
      volume->valueLo = rangeLo;
      volume->valueRange = rangeHi - rangeLo;
    }

    const std::string name = std::filesystem::path(path).stem().string();
    Scene scene = framedVolumeScene(name, box);
    Material none;
    none.name = "volume";
    const int32_t material = scene.addMaterial(none);
    for (const BrickEntry& e : bricks) {
      if (rank >= 0 && e.rank != rank) continue;
      uint64_t samples = 1;
      for (int a = 0; a < 3; ++a)
        samples *= uint64_t(std::min(e.hi[a], volume->dims[a] - 1) - std::max(e.lo[a] - 1, 0) + 1);
      std::error_code ec;
      const uint64_t size = std::filesystem::file_size(e.file, ec);
      if (ec) throw InputError(fmt::format("{}: cannot read ({})", e.file, ec.message()));
      if (size != samples * bytesPerSample)
        throw InputError(fmt::format(
            "{}: {} bytes, but the cells {},{},{}..{},{},{} and their ghost layer of {} need {}",
            e.file, size, e.lo[0], e.lo[1], e.lo[2], e.hi[0], e.hi[1], e.hi[2], format,
            samples * bytesPerSample));
      SharedArray<float> values;
      if (bytesPerSample == 4) {
        // float32: kept in the file's mapping, normalised where read (Volume::normalise).
        values = mappedFloats(e.file, samples);
      } else {
        // Read in chunks that stay in cache, converted as raw: volumes convert.
        ByteStream file = ByteStream::openFile(e.file);
        std::vector<float> converted(samples);
        constexpr uint64_t kChunk = 16384;
        std::vector<unsigned char> chunk(kChunk * bytesPerSample);
        for (uint64_t first = 0; first < samples; first += kChunk) {
          const uint64_t n = std::min(kChunk, samples - first);
          if (file.read(chunk.data(), n * bytesPerSample) != n * bytesPerSample)
            throw InputError(fmt::format("{}: read failed", e.file));
          float* out = converted.data() + first;
          if (bytesPerSample == 1)
            for (uint64_t i = 0; i < n; ++i) out[i] = float(chunk[i]) / 255.0f;
          else
            for (uint64_t i = 0; i < n; ++i)
              out[i] = float(uint16_t(chunk[2 * i] | (chunk[2 * i + 1] << 8))) / 65535.0f;
        }
        values = std::move(converted);
      }
      std::shared_ptr<VolumeBrick> brick;
      try {
        brick = std::make_shared<VolumeBrick>(volume, e.lo, e.hi, std::move(values));
      } catch (const InputError& error) {
        throw InputError(fmt::format("{}: {}", e.file, error.what()));
      }
      if (!(brick->majorant() > 0)) continue;  // it never collides: nothing to hold
      scene.addSingleInstanceGeometry(
          {fmt::format("{} brick {},{},{}", name, e.lo[0], e.lo[1], e.lo[2]), material,
           std::move(brick)});
    }
    return scene;
  } catch (const Json::exception& e) {
    fail(fmt::format("malformed ({})", e.what()));
  }
  return {};  // (not reached: fail throws)
}

}  // namespace ferry
