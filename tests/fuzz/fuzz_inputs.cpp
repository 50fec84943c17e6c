#include "fuzz/fuzz_inputs.h"

#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/error.h"
#include "core/hash64.h"
#include "io/byte_stream.h"
#include "io/checkpoints/checkpoint_file.h"
#include "io/gltf/gltf_loader.h"
#include "io/load_options.h"
#include "io/obj/obj_loader.h"
#include "io/parts/manifest.h"
#include "io/parts/part_file.h"
#include "io/pbrt/fourier_bsdf_file.h"
#include "io/pbrt/pbrt_parser.h"
#include "io/pbrt/pbrt_tokenizer.h"
#include "io/ply/ply_reader.h"
#include "io/volumes/volume_files.h"
#include "viewer/view_requests.h"

namespace ferry::fuzz {
namespace {

namespace fs = std::filesystem;

// A loader's options that keep one input within a fuzzer's memory and time
// limits (64 K generated triangles: well under 10 s with sanitizers) and say
// nothing.
LoadOptions quietOptions() {
  LoadOptions options;
  options.warn = [](const std::string&) {};
  options.maxGeneratedTriangles = 1 << 16;
  return options;
}

// The loaders that take a path get the bytes in a file of this process's
// own directory (removed at exit).
const fs::path& scratchDirectory() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("ferry-fuzz-" + std::to_string(getpid()));
    fs::create_directories(d);
    return d;
  }();
  static const struct Remover {
    ~Remover() {
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  } remover;
  return dir;
}

std::string writeScratch(const std::string& name, std::string_view bytes) {
  const fs::path path = scratchDirectory() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
  if (!out) throw std::runtime_error("fuzz: cannot write " + path.string());
  return path.string();
}

void pbrt(std::string_view bytes) {
  try {
    PbrtTokenizer tokens(ByteStream::fromMemory(bytes, "fuzz.pbrt"));
    while (tokens.next().kind != PbrtToken::Kind::End) {
    }
  } catch (const InputError&) {
  }
  // No directory with files: every Include, plymesh or texture is missing.
  loadPbrtFromString(bytes, "fuzz.pbrt", "/nonexistent-ferry-fuzz-dir", quietOptions());
}

void ply(std::string_view bytes) {
  ByteStream s = ByteStream::fromMemory(bytes, "fuzz.ply");
  readPly(s, quietOptions());
}

void obj(std::string_view bytes) {
  loadObj(writeScratch("fuzz.obj", bytes));
}
void gltf(std::string_view bytes) {
  loadGltf(writeScratch("fuzz.gltf", bytes), quietOptions());
}
void glb(std::string_view bytes) {
  loadGltf(writeScratch("fuzz.glb", bytes), quietOptions());
}

void bsdf(std::string_view bytes) {
  ByteStream s = ByteStream::fromMemory(bytes, "fuzz.bsdf");
  readFourierBsdf(s);
}

// Part files and checkpoints carry hashes of their bytes; a mutated input is
// sealed again (its hashes made to match) so that the fuzzer reaches the
// records behind them, not only the hash check.
void part(std::string_view bytes) {
  std::string sealed(bytes);
  constexpr size_t kHeaderBytes = 64, kHashedHeaderBytes = 40;
  constexpr size_t kFileBytesAt = 16, kPayloadHashAt = 24;
  if (sealed.size() >= kHeaderBytes) {
    const uint64_t fileBytes = sealed.size();
    std::memcpy(&sealed[kFileBytesAt], &fileBytes, 8);
    const uint64_t payload = hash64(sealed.data() + kHeaderBytes, sealed.size() - kHeaderBytes);
    std::memcpy(&sealed[kPayloadHashAt], &payload, 8);
    const uint64_t header = hash64(sealed.data(), kHashedHeaderBytes);
    std::memcpy(&sealed[kHashedHeaderBytes], &header, 8);
  }
  readPartFile(writeScratch("part.fpart", sealed));
}

void manifest(std::string_view bytes) {
  writeScratch("manifest.json", bytes);
  readManifest(scratchDirectory().string());
}

void checkpoint(std::string_view bytes) {
  std::string sealed(bytes);
  if (sealed.size() >= 8) {
    const uint64_t h = hash64(sealed.data(), sealed.size() - 8);
    std::memcpy(&sealed[sealed.size() - 8], &h, 8);
  }
  readCheckpoint(writeScratch("fuzz.ckpt", sealed));
}

CameraView someCamera(const char* name, Vec3f from) {
  CameraView c;
  c.name = name;
  c.from = from;
  c.at = Vec3f(0, 1, 0);
  c.up = Vec3f(0, 1, 0);
  c.fovY = 40;
  return c;
}

// The same body as a focus pick (POST /focus: x and y) and as a camera.
void camera(std::string_view bytes) {
  ViewChange change;
  try {
    applyFocusRequest(std::string(bytes), change);
  } catch (const RequestError&) {
  }
  applyCameraRequest(std::string(bytes), someCamera("default", Vec3f(0, 1, 5)), change);
}

void settings(std::string_view bytes) {
  RenderSettings current;
  current.width = 64;
  current.height = 48;
  current.samplesPerPixel = 1;
  current.maxDepth = 5;
  const std::vector<CameraView> views = {someCamera("default", Vec3f(0, 1, 5)),
                                         someCamera("top", Vec3f(0, 10, 0.1f))};
  ViewLimits limits;
  limits.volumeLook = true;  // the volume fields too
  ViewChange change;
  applySettingsRequest(std::string(bytes), current, views, limits, change);
}

// A raw volume: the first line is the name's query ("dims=2,2,2&format=
// uint8..."), the rest the file's bytes.
void raw(std::string_view bytes) {
  const size_t eol = bytes.find('\n');
  const std::string query(bytes.substr(0, eol));
  const std::string_view data = eol == std::string_view::npos ? "" : bytes.substr(eol + 1);
  loadRawVolume("raw:" + writeScratch("volume.raw", data) + "?" + query);
}

// A "bricks:" manifest; beside it b.raw, the 2x2x2 uint8 samples a brick
// of a 2^3 grid holds (or the 8 cells' bricks of a larger grid, in part).
void bricks(std::string_view bytes) {
  writeScratch("b.raw", std::string_view("\x00\x20\x40\x60\x80\xa0\xc0\xe0", 8));
  loadBrickPiece("bricks:" + writeScratch("fuzz.bricks.json", bytes), -1, 1);
}

void tf(std::string_view bytes) {
  readTransferFunction(writeScratch("fuzz.tf.json", bytes));
}

// An OpenVDB file: its density and temperature grids, each at most 4 M
// voxels when made dense (a few MiB, well inside a fuzzer's limits).
void vdb(std::string_view bytes) {
  readVdbDensityAndTemperature(writeScratch("fuzz.vdb", bytes), uint64_t(1) << 22);
}

// The fuzzer's bytes read in order, as little-endian numbers; zeros past the end.
class ByteReader {
 public:
  explicit ByteReader(std::string_view bytes) : bytes_(bytes) {}
  uint8_t byte() { return at_ < bytes_.size() ? uint8_t(bytes_[at_++]) : 0; }
  int16_t int16() { return int16_t(uint16_t(byte() | (uint16_t(byte()) << 8))); }
  float float32() {
    uint32_t u = 0;
    for (int i = 0; i < 4; ++i) u |= uint32_t(byte()) << (8 * i);
    float f;
    std::memcpy(&f, &u, 4);
    return f;
  }

 private:
  std::string_view bytes_;
  size_t at_ = 0;
};

// OpenVDB grids described by the bytes, written by OpenVDB and read back
// as a pbrt-v4 medium reads them (density and temperature): Ferry's reading
// of any grid OpenVDB writes, where mutating the file's bytes (vdb) finds
// OpenVDB's own behaviours. Per grid: name, value type, a scale per axis
// (n / 16), a rotation about z (a multiple of 30 degrees), a translation
// (n / 8), the background, then up to 64 active voxels (int16 coordinates,
// float values).
void vdbgrids(std::string_view bytes) {
  ByteReader in(bytes);
  static const char* const names[] = {"density", "temperature", "smoke", ""};
  std::vector<VdbGridToWrite> grids(1 + in.byte() % 3);
  for (VdbGridToWrite& g : grids) {
    g.name = names[in.byte() % 4];
    g.type = VdbGridToWrite::Type(in.byte() % 3);
    for (double& s : g.scale) s = int8_t(in.byte()) / 16.0;
    g.rotateZDegrees = (in.byte() % 4) * 30.0;
    for (double& t : g.translation) t = in.int16() / 8.0;
    g.background = in.float32();
    const int count = in.byte() % 65;
    for (int i = 0; i < count; ++i) {
      const std::array<int32_t, 3> c{in.int16(), in.int16(), in.int16()};
      g.voxels.emplace_back(c, in.float32());
    }
  }
  const std::string path = (scratchDirectory() / "fuzz-grids.vdb").string();
  writeVdbFile(path, grids);
  readVdbDensityAndTemperature(path, uint64_t(1) << 22);
}

}  // namespace

const std::vector<Kind>& kinds() {
  static const std::vector<Kind> all = {
      {"pbrt", pbrt},
      {"ply", ply},
      {"obj", obj},
      {"gltf", gltf},
      {"glb", glb},
      {"bsdf", bsdf},
      {"part", part},
      {"manifest", manifest},
      {"checkpoint", checkpoint},
      {"camera", camera},
      {"settings", settings},
      {"raw", raw},
      {"tf", tf},
      {"vdb", vdb},
      {"bricks", bricks},
      {"vdbgrids", vdbgrids},
  };
  return all;
}

const Kind& kind(std::string_view name) {
  for (const Kind& k : kinds())
    if (name == k.name) return k;
  throw std::invalid_argument("fuzz: no kind '" + std::string(name) + "'");
}

bool runOne(const Kind& k, std::string_view bytes) {
  try {
    k.run(bytes);
    return true;
  } catch (const InputError&) {
    return false;
  } catch (const RequestError&) {
    return false;
  }
}

}  // namespace ferry::fuzz
