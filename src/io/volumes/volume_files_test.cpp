// Volume files: OpenVDB grids, raw structured grids and transfer functions,
// read right (placement, values, normalisation) and refused with one clear
// error naming the file (tests/corpus/volumes).
#include "io/volumes/volume_files.h"

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.h"
#include "io/pbrt/pbrt_parser.h"
#include "io/scene_loader.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;
const fs::path kCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "volumes";

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

TEST(VdbFile, ReadsTheDensityGridWhereItIs) {
  const VdbDensity vdb = readVdbDensity((kCorpus / "density.vdb").string());
  EXPECT_EQ(vdb.gridName, "density");
  ASSERT_TRUE(vdb.grid);
  EXPECT_EQ(vdb.grid->nx(), 2);
  EXPECT_EQ(vdb.grid->ny(), 3);
  EXPECT_EQ(vdb.grid->nz(), 4);
  // Voxels (10..11, 20..22, 30..33) of size 0.5, each a cell about its centre.
  EXPECT_EQ(vdb.box.lower, Vec3f(4.75f, 9.75f, 14.75f));
  EXPECT_EQ(vdb.box.upper, Vec3f(5.75f, 11.25f, 16.75f));
  // Voxel (11, 22, 33) holds 0.25 x (1 + 2 + 3): the centre of the last cell.
  EXPECT_FLOAT_EQ(vdb.grid->lookup({0.75f, 5.0f / 6, 7.0f / 8}), 1.5f);
  const Scene scene = loadScene((kCorpus / "density.vdb").string());
  EXPECT_EQ(scene.media.size(), 1u);
  EXPECT_EQ(scene.mediumBoundaries.size(), 1u);
  EXPECT_EQ(scene.views.size(), 1u);
}

TEST(VdbFile, RefusesWhatIsNotADensity) {
  EXPECT_NE(errorOf([] {
              readVdbDensity((kCorpus / "negative_density.vdb").string());
            }).find("voxel (1, 0, 0) is -2"),
            std::string::npos);
  const std::string none =
      errorOf([] { readVdbDensity((kCorpus / "no_float_grid.vdb").string()); });
  EXPECT_NE(none.find("no float grid"), std::string::npos) << none;
  EXPECT_NE(none.find("velocity"), std::string::npos) << none;
  EXPECT_NE(errorOf([] {
              readVdbDensity((kCorpus / "not_vdb.vdb").string());
            }).find("not_vdb.vdb: not a readable OpenVDB file"),
            std::string::npos);
  EXPECT_NE(errorOf([] {
              readVdbDensity((kCorpus / "density.vdb").string(), "temperature");
            }).find("no float grid named \"temperature\""),
            std::string::npos);
}

// A sparse grid is read dense over its active box: a box larger than the
// limit is refused before anything is allocated, its size counted in 64 bits.
TEST(VdbFile, RefusesASparseGridTooLargeToMakeDense) {
  const std::string far =
      errorOf([] { readVdbDensity((kCorpus / "sparse_far_apart.vdb").string()); });
  EXPECT_NE(far.find("sparse_far_apart.vdb: grid \"density\" spans 100001 x 100001 x 100001 "
                     "voxels, more than the 17179869184 read as a dense grid"),
            std::string::npos)
      << far;
  const std::string density = (kCorpus / "density.vdb").string();  // 2 x 3 x 4 voxels
  EXPECT_NE(errorOf([&] { readVdbDensity(density, "", 23); }).find("spans 2 x 3 x 4 voxels"),
            std::string::npos);
  EXPECT_EQ(readVdbDensity(density, "", 24).grid->nz(), 4);
}

// What writeVdbFile writes reads back where it was put; what the reader
// refuses (a rotation, a mirror, a scale OpenVDB refuses) says so.
TEST(VdbFile, WrittenGridsReadBackWhereTheyWerePut) {
  const std::string path =
      (fs::temp_directory_path() / ("ferry-vdb-" + std::to_string(getpid()) + ".vdb")).string();
  VdbGridToWrite density;
  density.name = "density";
  density.scale = {0.5, 1, 2};
  density.translation = {1, 2, 3};
  density.voxels = {{{0, 0, 0}, 0.5f}, {{1, 0, 0}, 1.5f}};
  VdbGridToWrite temperature = density;
  temperature.name = "temperature";
  temperature.type = VdbGridToWrite::Type::Double;  // not a float grid: no temperature
  writeVdbFile(path, {density, temperature});
  const auto [d, t] = readVdbDensityAndTemperature(path);
  ASSERT_TRUE(d.grid);
  EXPECT_FALSE(t.grid);
  EXPECT_EQ(d.grid->nx(), 2);
  EXPECT_EQ(d.grid->ny(), 1);
  // Cells about their centres: x from -0.25 to 0.75, y -0.5..0.5, z -1..1, moved by (1, 2, 3).
  EXPECT_EQ(d.box.lower, Vec3f(0.75f, 1.5f, 2.0f));
  EXPECT_EQ(d.box.upper, Vec3f(1.75f, 2.5f, 4.0f));
  EXPECT_FLOAT_EQ(d.grid->lookup({0.75f, 0.5f, 0.5f}), 1.5f);
  density.rotateZDegrees = 30;
  writeVdbFile(path, {density});
  EXPECT_NE(errorOf([&] { readVdbDensity(path); }).find("is rotated or sheared"),
            std::string::npos);
  density.rotateZDegrees = 0;
  density.scale = {-1, 1, 1};
  writeVdbFile(path, {density});
  EXPECT_NE(errorOf([&] { readVdbDensity(path); }).find("is mirrored"), std::string::npos);
  density.scale = {0, 1, 1};
  EXPECT_NE(errorOf([&] { writeVdbFile(path, {density}); }).find("cannot write the grids"),
            std::string::npos);
  fs::remove(path);
}

// The dense copy holds every voxel of the active box, x fastest: the
// stored values where voxels were set, the background elsewhere, across
// several of OpenVDB's leaf (8^3) and internal nodes.
TEST(VdbFile, DenseCopyHoldsEveryVoxelOfTheActiveBox) {
  const std::string path =
      (fs::temp_directory_path() / ("ferry-vdb-dense-" + std::to_string(getpid()) + ".vdb"))
          .string();
  VdbGridToWrite g;
  g.name = "density";
  g.background = 0.25f;
  std::map<std::array<int32_t, 3>, float> set;
  for (int i = 0; i < 200; ++i) {
    const std::array<int32_t, 3> c{-20 + (i * 37) % 61, -9 + (i * 11) % 23, 5 + (i * 7) % 150};
    set[c] = float(i % 17) * 0.5f;
  }
  for (const auto& [c, v] : set) g.voxels.emplace_back(c, v);
  writeVdbFile(path, {g});
  const VdbDensity d = readVdbDensity(path);
  fs::remove(path);
  ASSERT_TRUE(d.grid);
  std::array<int32_t, 3> lo = set.begin()->first, hi = lo;
  for (const auto& [c, v] : set)
    for (int a = 0; a < 3; ++a)
      lo[size_t(a)] = std::min(lo[size_t(a)], c[size_t(a)]),
      hi[size_t(a)] = std::max(hi[size_t(a)], c[size_t(a)]);
  ASSERT_EQ(d.grid->nx(), hi[0] - lo[0] + 1);
  ASSERT_EQ(d.grid->ny(), hi[1] - lo[1] + 1);
  ASSERT_EQ(d.grid->nz(), hi[2] - lo[2] + 1);
  size_t wrong = 0, i = 0;
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x, ++i) {
        const auto it = set.find({x, y, z});
        wrong += d.grid->values()[i] != (it == set.end() ? g.background : it->second);
      }
  EXPECT_EQ(wrong, 0u);
}

TEST(VdbFile, PbrtNanovdbMediaReadTheSameGridFromVdb) {
  const std::string text =
      "MakeNamedMedium \"cloud\" \"string type\" \"nanovdb\" \"string filename\" "
      "\"density.vdb\" \"rgb sigma_s\" [2 2 2]\nWorldBegin\n";
  const Scene s = loadPbrtFromString(text, "cloud.pbrt", kCorpus.string());
  ASSERT_EQ(s.media.size(), 1u);
  EXPECT_EQ(s.media[0].density->nx(), 2);
  EXPECT_EQ(s.media[0].sigmaS, Vec3f(2));
  EXPECT_FALSE(s.media[0].emits());  // density.vdb has no temperature grid
}

TEST(VdbFile, PbrtNanovdbMediaEmitByTheirTemperatureGrid) {
  // fire.vdb: 4^3 voxels 0.5 apart of density 1 and temperature 3000 K.
  const std::string text =
      "MakeNamedMedium \"fire\" \"string type\" \"nanovdb\" \"string filename\" "
      "\"fire.vdb\" \"float Lescale\" 2 \"float temperaturescale\" 2\nWorldBegin\n";
  const Scene s = loadPbrtFromString(text, "fire.pbrt", kCorpus.string());
  ASSERT_EQ(s.media.size(), 1u);
  const Medium& m = s.media[0];
  ASSERT_TRUE(m.temperature);
  EXPECT_EQ(m.emission, Vec3f(2));
  // 6000 K at the centre, twice Lescale: a blackbody a little warmer than white.
  const Vec3f e = m.emittedAt({0.5f, 0.5f, 0.5f});
  EXPECT_GT(e.x, 0);
  EXPECT_NEAR(e.x / e.z, 1.1, 0.15) << e.x << " " << e.y << " " << e.z;
}

// A .nvdb file written by NanoVDB reads back voxel for voxel, over its
// active box, each voxel a cell centred on its index; pbrt's nanovdb medium
// and `ferry render x.nvdb` read it; a file without "density" names itself.
TEST(NanoVdbFile, ReadsBackWhatWasWritten) {
  const std::string path =
      (fs::temp_directory_path() / ("ferry-nvdb-" + std::to_string(getpid()) + ".nvdb")).string();
  NanoVdbGridToWrite density{"density", {4, 3, 2}, {10, -2, 5}, 0.5f, {}};
  for (int i = 0; i < 24; ++i) density.values.push_back(float(i + 1) * 0.25f);
  NanoVdbGridToWrite kelvin{"temperature", {2, 2, 2}, {0, 0, 0}, 0.5f, std::vector<float>(8, 3000)};
  writeNanoVdbFile(path, {density, kelvin});
  const auto [d, t] = readNanoVdbDensityAndTemperature(path);
  ASSERT_TRUE(d.grid);
  EXPECT_EQ(d.grid->nx(), 4);
  EXPECT_EQ(d.grid->ny(), 3);
  EXPECT_EQ(d.grid->nz(), 2);
  EXPECT_EQ(d.grid->values(), density.values);
  EXPECT_NEAR(d.box.lower.x, (10 - 0.5f) * 0.5f, 1e-5f);
  EXPECT_NEAR(d.box.upper.y, (-2 + 3 - 0.5f) * 0.5f, 1e-5f);
  EXPECT_NEAR(d.box.upper.z, (5 + 2 - 0.5f) * 0.5f, 1e-5f);
  ASSERT_TRUE(t.grid);
  EXPECT_EQ(t.grid->values(), kelvin.values);
  const std::string text =
      "MakeNamedMedium \"fire\" \"string type\" \"nanovdb\" "
      "\"string filename\" \"" +
      path + "\"\nWorldBegin\n";
  const Scene s = loadPbrtFromString(text, "fire.pbrt", kCorpus.string());
  ASSERT_EQ(s.media.size(), 1u);
  EXPECT_EQ(s.media[0].density->values(), density.values);
  EXPECT_TRUE(s.media[0].temperature);
  const Scene rendered = loadScene(path);
  ASSERT_EQ(rendered.media.size(), 1u);
  writeNanoVdbFile(path, {kelvin});
  try {
    readNanoVdbDensityAndTemperature(path);
    ADD_FAILURE() << "a file without a density grid was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("density"), std::string::npos) << e.what();
  }
  std::ofstream(path, std::ios::trunc) << "not a grid";
  EXPECT_THROW(readNanoVdbDensityAndTemperature(path), InputError);
  fs::remove(path);
  EXPECT_THROW(readNanoVdbDensityAndTemperature(path), InputError);
}

class RawFile {
 public:
  explicit RawFile(const std::vector<unsigned char>& bytes)
      : path_((fs::temp_directory_path() /
               ("ferry-raw-" + std::to_string(::getpid()) + "-" + std::to_string(next_++)))
                  .string()) {
    std::ofstream(path_, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  }
  ~RawFile() { fs::remove(path_); }
  const std::string& path() const { return path_; }

 private:
  static inline int next_ = 0;
  std::string path_;
};

TEST(RawVolume, NormalisesEachFormatAndPlacesTheBox) {
  RawFile u8({0, 255, 51, 102, 0, 0, 0, 0});
  Scene s = loadScene("raw:" + u8.path() + "?dims=2,2,2&format=uint8&spacing=0.5,1,2&origin=1,2,3");
  ASSERT_EQ(s.media.size(), 1u);
  const Medium& m = s.media[0];
  ASSERT_TRUE(m.transfer);
  EXPECT_FLOAT_EQ(m.density->values()[1], 1.0f);
  EXPECT_FLOAT_EQ(m.density->values()[2], 0.2f);
  // The box: dims x spacing from the origin.
  EXPECT_EQ(m.gridFromWorld.transformPoint({1, 2, 3}), Vec3f(0));
  EXPECT_EQ(m.gridFromWorld.transformPoint({2, 4, 7}), Vec3f(1));
  RawFile u16({0xff, 0xff, 0, 0});
  s = loadScene("raw:" + u16.path() + "?dims=2,1,1&format=uint16");
  EXPECT_FLOAT_EQ(s.media[0].density->values()[0], 1.0f);
  std::vector<unsigned char> floats(12);
  const float f[3] = {-1, 3, 1};
  std::memcpy(floats.data(), f, 12);
  RawFile f32(floats);
  s = loadScene("raw:" + f32.path() + "?dims=3,1,1&format=float32");
  EXPECT_EQ(s.media[0].density->values(), (std::vector<float>{0, 1, 0.5f}));
  // A range wider than a float holds (a fuzzer's finding: NaN densities).
  const float wide[3] = {-3e38f, 3e38f, 0};
  std::memcpy(floats.data(), wide, 12);
  RawFile f32wide(floats);
  s = loadScene("raw:" + f32wide.path() + "?dims=3,1,1&format=float32");
  EXPECT_EQ(s.media[0].density->values(), (std::vector<float>{0, 1, 0.5f}));
}

TEST(RawVolume, ATransferFunctionFileAndOpacityScale) {
  RawFile u8({0, 255});
  const std::string tf = (kCorpus / "ramp.tf.json").string();
  const Scene s = loadScene("raw:" + u8.path() + "?dims=2,1,1&format=uint8&tf=" + tf);
  const TransferFunction& t = *s.media[0].transfer;
  EXPECT_NEAR(t.color(0.5f).x, 0.6f, 1e-6f);
  // Its scale (5 mean free paths at opacity 1) across the box's longest side (2).
  EXPECT_FLOAT_EQ(t.scale(), 2.5f);
  const Scene scaled =
      loadScene("raw:" + u8.path() + "?dims=2,1,1&format=uint8&tf=" + tf + "&opacity=8");
  EXPECT_FLOAT_EQ(scaled.media[0].transfer->scale(), 4.0f);
}

TEST(RawVolume, RefusesMalformedNames) {
  RawFile u8(std::vector<unsigned char>(8, 1));
  const std::string base = "raw:" + u8.path();
  auto expect = [&](const std::string& spec, const std::string& piece) {
    const std::string e = errorOf([&] { loadScene(spec); });
    EXPECT_NE(e.find(piece), std::string::npos) << spec << ": " << e;
  };
  expect(base + "?dims=2,2,3&format=uint8", "8 bytes, but dims 2x2x3 of uint8 need 12");
  expect(base + "?dims=4294967296,4294967296,2&format=uint8", "overflow");
  expect(base + "?dims=2,2&format=uint8", "expected three positive integers");
  expect(base + "?dims=2,2,2&format=int7", "format 'int7'");
  expect(base + "?format=uint8", "no dims");
  expect(base + "?dims=2,2,2&format=uint8&colour=red", "unknown key 'colour'");
  expect(base + "?dims=2,2,2&format=uint8&opacity=-1", "opacity '-1'");
  expect("raw:/no/such/file?dims=1,1,1&format=uint8", "/no/such/file: cannot read");
  std::vector<unsigned char> nan(8);
  const float v[2] = {1, std::numeric_limits<float>::quiet_NaN()};
  std::memcpy(nan.data(), v, 8);
  RawFile withNan(nan);
  expect("raw:" + withNan.path() + "?dims=2,1,1&format=float32", "sample 1 (x 1, y 0, z 0) is nan");
  expect(base + "?dims=2,2,2&format=uint8&tf=" + (kCorpus / "bad_order.tf.json").string(),
         "positions must increase");
  expect(base + "?dims=2,2,2&format=uint8&tf=" + (kCorpus / "short_color.tf.json").string(),
         "\"colors\" entry 0 is not 4 numbers");
}

// JSON numbers a field's type cannot hold (found by fuzzing: 2.5e50 samples
// converted to int64_t) are the file's error, not a conversion.
// A directory opens as a stream on Linux and throws from its first read,
// past the JSON parser (a fuzzer's finding: "tf=/"); it is the file's error.
TEST(VolumeJson, ADirectoryOrAMissingFileIsTheFilesError) {
  const std::string dir = ::testing::TempDir();
  EXPECT_NE(errorOf([&] {
              readTransferFunction(dir);
            }).find(": cannot read the transfer function: not a regular file"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              loadBrickPiece("bricks:" + dir, 0, 1);
            }).find(": cannot read the brick manifest: not a regular file"),
            std::string::npos);
  EXPECT_NE(errorOf([&] {
              readTransferFunction(dir + "/no-such.tf.json");
            }).find("no-such.tf.json: cannot read the transfer function: no such file"),
            std::string::npos);
}

TEST(VolumeJson, NumbersThatDoNotFitTheirFieldAreRefused) {
  auto text = [](const std::string& t) {
    return RawFile(std::vector<unsigned char>(t.begin(), t.end()));
  };
  const RawFile tf = text(R"({"colors":[[0,1,1,1]],"opacity":[[0,1e300]]})");
  EXPECT_NE(errorOf([&] {
              readTransferFunction(tf.path());
            }).find("\"opacity\" entry 0 is not 2 numbers"),
            std::string::npos);
  const RawFile scale = text(R"({"colors":[[0,1,1,1]],"opacity":[[0,1]],"scale":-1e39})");
  EXPECT_NE(
      errorOf([&] { readTransferFunction(scale.path()); }).find("\"scale\" is not a finite number"),
      std::string::npos);
  for (const auto& [manifest, error] : std::vector<std::pair<std::string, std::string>>{
           {R"({"dims":[2,2,2.5e50],"format":"uint8","bricks":[]})",
            "dims: expected three numbers that fit"},
           {R"({"dims":[2,2,2],"spacing":[1,1e300,1],"format":"uint8","bricks":[]})",
            "spacing: expected three numbers that fit"},
           {R"({"dims":[2,2,2],"format":"float32","range":[0,1e39],"bricks":[]})",
            "range: expected finite LO <= HI"},
           {R"({"dims":[2,2,2],"format":"float32","range":[-3e38,3e38],"bricks":[]})",
            "range: HI - LO is more than a float holds"}}) {
    const RawFile f = text(manifest);
    EXPECT_NE(errorOf([&] { loadBrickPiece("bricks:" + f.path(), 0, 1); }).find(error),
              std::string::npos)
        << manifest;
  }
}

}  // namespace
}  // namespace ferry
