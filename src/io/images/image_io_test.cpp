#include "io/images/image_io.h"

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <ImfHeader.h>
#include <ImfRgbaFile.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/half.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

const fs::path kImages = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "images";
const fs::path kObjCorpus = fs::path(FERRY_SOURCE_DIR) / "tests" / "corpus" / "obj";

std::string image(const std::string& name) {
  return (kImages / name).string();
}

class TempDir {
 public:
  TempDir() {
    path_ =
        fs::temp_directory_path() / ("ferry_image_test_" + std::to_string(::getpid()) + "_" +
                                     testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }
  // Every name in the directory, hidden temporaries included.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(path_))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  fs::path path_;
};

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// The message of the InputError `f` throws; fails the test otherwise.
template <typename F>
std::string inputError(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected an InputError, got: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no exception";
  return {};
}

bool contains(const std::string& s, const std::string& piece) {
  return s.find(piece) != std::string::npos;
}

LinearImage testImage(int width, int height) {
  LinearImage image;
  image.width = width;
  image.height = height;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      image.rgb.push_back(
          {0.01f * x + 0.5f * y, float(x * y) - 3.0f, 1e-3f * float(x + 1) * 7.77f});
  return image;
}

// ------------------------------------------------------------ malformed images

struct BadImage {
  std::string file;
  std::string contains;
};

class TextureCorpusError : public testing::TestWithParam<BadImage> {};

TEST_P(TextureCorpusError, NamesFileAndReason) {
  const std::string path = image(GetParam().file);
  std::string message = inputError([&] { readTexture(path); });
  RecordProperty("message", message);
  EXPECT_TRUE(contains(message, path + ": ")) << message;
  EXPECT_TRUE(contains(message, GetParam().contains)) << message;
  // readHdrImage goes through the same reader for 8-bit formats.
  std::string hdrMessage = inputError([&] { readHdrImage(path); });
  EXPECT_EQ(hdrMessage, message);
}

INSTANTIATE_TEST_SUITE_P(
    Corpus, TextureCorpusError,
    testing::Values(BadImage{"truncated.png",
                             "cannot decode image: outofdata (corrupt or truncated file?)"},
                    BadImage{"empty.png", "cannot read image: empty file"},
                    BadImage{"beyond_stb.png",
                             "cannot read image: corrupt, unsupported or too large PNG header"},
                    BadImage{"not_an_image.png", "cannot read image: unknown image type"},
                    BadImage{"huge_header.png", "impossible for a file of 68 bytes"},
                    BadImage{"too_large.png", "larger than Ferry accepts"},
                    BadImage{"no_such_image.png", "no such file"}));

class PfmCorpusError : public testing::TestWithParam<BadImage> {};

TEST_P(PfmCorpusError, NamesFileAndReason) {
  const std::string path = image(GetParam().file);
  std::string message = inputError([&] { readPfm(path); });
  RecordProperty("message", message);
  EXPECT_TRUE(contains(message, path + ": ")) << message;
  EXPECT_TRUE(contains(message, GetParam().contains)) << message;
}

INSTANTIATE_TEST_SUITE_P(
    Corpus, PfmCorpusError,
    testing::Values(
        BadImage{"lying_size.pfm",
                 "header says 1000x1000 with 3 channel(s) (12000000 bytes of samples) but the file "
                 "holds 36 bytes"},
        BadImage{"extra_data.pfm", "(12 bytes of samples) but the file holds 24 bytes"},
        BadImage{"bad_magic.pfm", "does not start with 'PF' or 'Pf'"},
        BadImage{"bad_scale.pfm", "the scale 'abc' is not a finite non-zero number"},
        BadImage{"zero_scale.pfm", "the scale '0' is not a finite non-zero number"},
        BadImage{"negative_width.pfm", "the width -4 is out of range"},
        BadImage{"header_only.pfm", "expected whitespace before the scale"},
        BadImage{"empty.pfm", "does not start with 'PF' or 'Pf'"},
        BadImage{"no_such_image.pfm", "no such file"}));

TEST(ImageIo, EveryCorpusImageIsCovered) {
  std::set<std::string> covered = {"truncated.png",   "empty.png",       "not_an_image.png",
                                   "huge_header.png", "too_large.png",   "beyond_stb.png",
                                   "lying_size.pfm",  "extra_data.pfm",  "bad_magic.pfm",
                                   "bad_scale.pfm",   "zero_scale.pfm",  "negative_width.pfm",
                                   "header_only.pfm", "empty.pfm",       "little_rgb.pfm",
                                   "big_grey.pfm",    "not_an_image.exr"};
  for (const auto& entry : fs::directory_iterator(kImages))
    EXPECT_TRUE(covered.count(entry.path().filename().string())) << entry.path();
}

TEST(ImageIo, NotAnExr) {
  std::string path = image("not_an_image.exr");
  std::string message = inputError([&] { readHdrImage(path); });
  EXPECT_TRUE(contains(message, path + ": cannot read EXR: ")) << message;
}

TEST(ImageIo, UnknownExtensions) {
  EXPECT_TRUE(contains(inputError([] { readHdrImage("picture.gif"); }),
                       "picture.gif: unsupported image format '.gif'"));
  TempDir dir;
  std::string path = dir.file("out.tiff");
  EXPECT_TRUE(contains(inputError([&] { writeImage(path, testImage(2, 2)); }),
                       "out.tiff: unsupported output format '.tiff'"));
  EXPECT_TRUE(dir.entries().empty());
}

// ------------------------------------------------------------------ good images

TEST(ImageIo, FormatOfAFileNameIsItsExtensionInAnyCase) {
  EXPECT_EQ(imageFormatOf("out.png"), ImageFormat::Png);
  EXPECT_EQ(imageFormatOf("out.PNG"), ImageFormat::Png);
  EXPECT_EQ(imageFormatOf("dir.d/Out.Png"), ImageFormat::Png);
  EXPECT_EQ(imageFormatOf("a/b.exr"), ImageFormat::Exr);
  EXPECT_EQ(imageFormatOf("b.EXR"), ImageFormat::Exr);
  EXPECT_EQ(imageFormatOf("c.pfm"), ImageFormat::Pfm);
  EXPECT_EQ(imageFormatOf("c.PfM"), ImageFormat::Pfm);
  EXPECT_EQ(imageFormatOf("x.png.gif"), std::nullopt);
  EXPECT_EQ(imageFormatOf("x.jpg"), std::nullopt);  // read, never written
  EXPECT_EQ(imageFormatOf("png"), std::nullopt);
  EXPECT_EQ(imageFormatOf("dir.png/image"), std::nullopt);
  EXPECT_EQ(imageFormatOf(""), std::nullopt);
  EXPECT_EQ(lowerCaseExtension("a/B.GiF"), ".gif");
  EXPECT_EQ(lowerCaseExtension("noext"), "");
}

TEST(ImageIo, ReadPfmLittleEndianRgb) {
  LinearImage img = readPfm(image("little_rgb.pfm"));
  ASSERT_EQ(img.width, 2);
  ASSERT_EQ(img.height, 1);
  EXPECT_EQ(img.rgb[0], Vec3f(0.5f, 1.0f, 2.0f));
  EXPECT_EQ(img.rgb[1], Vec3f(-3.0f, 4.25f, 1e6f));
}

TEST(ImageIo, ReadPfmBigEndianGreyBottomToTop) {
  LinearImage img = readPfm(image("big_grey.pfm"));
  ASSERT_EQ(img.width, 1);
  ASSERT_EQ(img.height, 2);
  EXPECT_EQ(img.rgb[0], Vec3f(8.0f));   // top row: stored last
  EXPECT_EQ(img.rgb[1], Vec3f(0.25f));  // bottom row: stored first
}

TEST(ImageIo, ReadHdrImageFromPngIsLinear) {
  HdrImage img = readHdrImage((kObjCorpus / "checker.png").string());
  ASSERT_EQ(img.width, 4);
  ASSERT_EQ(img.height, 4);
  EXPECT_EQ(img.at(0, 0), Vec3f(1, 0, 0));
  EXPECT_EQ(img.at(1, 0), Vec3f(0, 0, 1));
}

TEST(ImageIo, ReadHdrImageRejectsNonFiniteAndClampsNegative) {
  TempDir dir;
  LinearImage img = testImage(3, 2);
  img.rgb[0] = {-2.0f, 1.0f, 0.5f};
  writePfm(dir.file("negative.pfm"), img);
  HdrImage hdr = readHdrImage(dir.file("negative.pfm"));
  EXPECT_EQ(hdr.at(0, 0), Vec3f(0.0f, 1.0f, 0.5f));
  img.rgb[4].y = std::nanf("");
  writePfm(dir.file("nan.pfm"), img);
  EXPECT_TRUE(contains(inputError([&] { readHdrImage(dir.file("nan.pfm")); }),
                       "nan.pfm: pixel (1, 1) is not finite"));
}

TEST(ImageIo, ReadAlphaTexture) {
  Texture grey = readAlphaTexture((kObjCorpus / "mask_grey.png").string());
  ASSERT_EQ(grey.rgba.size(), 64u);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_EQ(grey.rgba[size_t(y * 4 + x) * 4 + 3], y < 2 ? 255 : 0);
  // An image with an alpha channel keeps it.
  Texture rgba = readAlphaTexture((kObjCorpus / "mask_rgba.png").string());
  EXPECT_EQ(rgba.rgba[3], 255);
  EXPECT_EQ(rgba.rgba[7], 0);
  EXPECT_EQ(rgba.rgba[11], 128);
  EXPECT_EQ(rgba.rgba[15], 64);
  // Plain readTexture of a grey image: opaque.
  EXPECT_EQ(readTexture((kObjCorpus / "mask_grey.png").string()).rgba[63], 255);
}

// ------------------------------------------------------------------ round trips

TEST(ImageIo, PngRoundTripIsExact) {
  TempDir dir;
  const int w = 7, h = 5;
  std::vector<uint8_t> rgba(size_t(w * h * 4));
  for (size_t i = 0; i < rgba.size(); ++i) rgba[i] = uint8_t((i * 37 + i / 5) % 256);
  writePng(dir.file("a.png"), w, h, rgba);
  Texture t = readTexture(dir.file("a.png"));
  EXPECT_EQ(t.width, w);
  EXPECT_EQ(t.height, h);
  EXPECT_EQ(t.name, dir.file("a.png"));
  EXPECT_EQ(t.rgba, rgba);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"a.png"});
}

TEST(ImageIo, WriteImagePngIsSrgbEncoded) {
  TempDir dir;
  LinearImage img;
  img.width = 4;
  img.height = 1;
  img.rgb = {{0, 0.5f, 1}, {2, -1, std::nanf("")}, {0.21586f, 0.0031308f, 1e-9f}, {1, 1, 1}};
  writeImage(dir.file("b.PNG"), img);
  Texture t = readTexture(dir.file("b.PNG"));
  std::vector<uint8_t> expected = {0,   188, 255, 255, 255, 0,   0,   255,
                                   128, 10,  0,   255, 255, 255, 255, 255};
  EXPECT_EQ(t.rgba, expected);
}

TEST(ImageIo, ExrRoundTripWithinHalfPrecision) {
  TempDir dir;
  LinearImage img = testImage(9, 70);    // more rows than one read band
  img.rgb[5] = {1e6f, -1e6f, 65504.0f};  // saturates rather than overflowing
  writeExr(dir.file("c.exr"), img);
  HdrImage back = readHdrImage(dir.file("c.exr"));
  ASSERT_EQ(back.width, img.width);
  ASSERT_EQ(back.height, img.height);
  for (size_t i = 0; i < img.rgb.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      float v = img.rgb[i][k];
      // Exactly Ferry's half rounding, then negatives clamped by readHdrImage.
      float expected = std::max(halfToFloat(floatToHalf(v)), 0.0f);
      ASSERT_EQ(back.pixels[i][k], expected) << i << " " << k;
      if (v > 0 && v < 65504) {
        ASSERT_LE(std::abs(back.pixels[i][k] - v), std::max(std::abs(v) * 0x1p-11f, 0x1p-24f));
      }
    }
  }
  EXPECT_EQ(back.pixels[5], Vec3f(65504.0f, 0.0f, 65504.0f));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"c.exr"});
}

TEST(ImageIo, ExrWithOffsetDataWindow) {
  TempDir dir;
  // Written through OpenEXR directly: data window (10, 20)-(12, 90), RGBA.
  const int w = 3, h = 71;
  Imath::Box2i window({10, 20}, {10 + w - 1, 20 + h - 1});
  Imf::Header header(window, window);
  std::vector<Imf::Rgba> pixels;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) pixels.emplace_back(float(x), float(y), 0.5f, 1.0f);
  {
    Imf::RgbaOutputFile out(dir.file("d.exr").c_str(), header, Imf::WRITE_RGBA);
    out.setFrameBuffer(pixels.data() - (10 + 20 * w), 1, w);
    out.writePixels(h);
  }
  HdrImage img = readHdrImage(dir.file("d.exr"));
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.height, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      ASSERT_EQ(img.at(x, y), Vec3f(float(x), float(y), 0.5f)) << x << "," << y;
}

TEST(ImageIo, TruncatedExr) {
  TempDir dir;
  writeExr(dir.file("e.exr"), testImage(64, 64));
  std::string bytes = readFile(dir.file("e.exr"));
  writeFile(dir.file("e.exr"), bytes.substr(0, bytes.size() / 2));
  std::string message = inputError([&] { readHdrImage(dir.file("e.exr")); });
  EXPECT_TRUE(contains(message, dir.file("e.exr") + ": cannot read EXR: ")) << message;
}

TEST(ImageIo, ExrWithLyingDataWindow) {
  TempDir dir;
  writeExr(dir.file("h.exr"), testImage(4, 4));
  std::string bytes = readFile(dir.file("h.exr"));
  // The header holds "dataWindow\0box2i\0", a size of 16, then xMin yMin xMax yMax.
  const std::string key("dataWindow\0box2i\0", 17);
  size_t at = bytes.find(key);
  ASSERT_NE(at, std::string::npos);
  for (int32_t side : {100000000, 40000}) {
    std::string patched = bytes;
    for (size_t field : {2u, 3u}) {  // xMax, yMax
      uint32_t v = uint32_t(side);
      for (int b = 0; b < 4; ++b)
        patched[at + key.size() + 4 + 4 * field + b] = char((v >> (8 * b)) & 0xff);
    }
    writeFile(dir.file("h.exr"), patched);
    std::string message = inputError([&] { readHdrImage(dir.file("h.exr")); });
    RecordProperty("message" + std::to_string(side), message);
    EXPECT_TRUE(contains(message, dir.file("h.exr") + ": ")) << message;
    // Caught by OpenEXR's size limit (1e8) or its missing line-offset table (4e4),
    // before any pixel buffer is allocated.
    EXPECT_TRUE(contains(message, "cannot read EXR: ")) << message;
  }
}

TEST(ImageIo, PfmRoundTripIsExact) {
  TempDir dir;
  LinearImage img = testImage(5, 3);
  img.rgb[7] = {-0.0f, std::numeric_limits<float>::denorm_min(), 3.4e38f};
  writePfm(dir.file("f.pfm"), img);
  LinearImage back = readPfm(dir.file("f.pfm"));
  ASSERT_EQ(back.width, 5);
  ASSERT_EQ(back.height, 3);
  ASSERT_EQ(back.rgb.size(), img.rgb.size());
  EXPECT_EQ(std::memcmp(back.rgb.data(), img.rgb.data(), img.rgb.size() * sizeof(Vec3f)), 0);

  // The layout the format prescribes: header, then little-endian floats, bottom row first.
  std::string bytes = readFile(dir.file("f.pfm"));
  const std::string head = "PF\n5 3\n-1.0\n";
  ASSERT_EQ(bytes.substr(0, head.size()), head);
  ASSERT_EQ(bytes.size(), head.size() + 5 * 3 * 3 * 4);
  const unsigned char* first = reinterpret_cast<const unsigned char*>(bytes.data() + head.size());
  uint32_t bits = uint32_t(first[0]) | uint32_t(first[1]) << 8 | uint32_t(first[2]) << 16 |
                  uint32_t(first[3]) << 24;
  float bottomLeftRed;
  std::memcpy(&bottomLeftRed, &bits, 4);
  EXPECT_EQ(bottomLeftRed, img.rgb[2 * 5].x);
}

TEST(ImageIo, WriteImageDispatchesOnExtension) {
  TempDir dir;
  LinearImage img = testImage(3, 2);
  writeImage(dir.file("g.pfm"), img);
  writeImage(dir.file("g.exr"), img);
  writeImage(dir.file("g.png"), img);
  EXPECT_EQ(readPfm(dir.file("g.pfm")).rgb[4], img.rgb[4]);
  EXPECT_EQ(readHdrImage(dir.file("g.exr")).pixels[1].x, halfToFloat(floatToHalf(img.rgb[1].x)));
  EXPECT_EQ(readTexture(dir.file("g.png")).rgba, toPng(img));
  EXPECT_EQ(dir.entries(), (std::vector<std::string>{"g.exr", "g.pfm", "g.png"}));
}

// --------------------------------------------------------- atomic replacement

TEST(ImageIo, AtomicWriteKeepsOldFileWhenWriterThrows) {
  TempDir dir;
  const std::string target = dir.file("image.png");
  writeFile(target, "the good old image");
  std::string seenTemp;
  EXPECT_THROW(writeFileAtomically(target,
                                   [&](const std::string& temp) {
                                     seenTemp = temp;
                                     writeFile(temp, "half of a new ima");
                                     throw InputError("disk full, say");
                                   }),
               InputError);
  EXPECT_EQ(readFile(target), "the good old image");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"image.png"});
  // The temporary was a hidden sibling of the target.
  EXPECT_EQ(fs::path(seenTemp).parent_path(), dir.path());
  EXPECT_EQ(fs::path(seenTemp).filename().string().rfind(".image.png.tmp.", 0), 0u) << seenTemp;

  // Any exception, not just InputError.
  EXPECT_THROW(writeFileAtomically(target, [](const std::string&) { throw std::bad_alloc(); }),
               std::bad_alloc);
  EXPECT_EQ(readFile(target), "the good old image");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"image.png"});
}

TEST(ImageIo, AtomicWriteReplacesOnSuccess) {
  TempDir dir;
  const std::string target = dir.file("out.pfm");
  writeFile(target, "old");
  writeFileAtomically(target, [](const std::string& temp) { writeFile(temp, "new contents"); });
  EXPECT_EQ(readFile(target), "new contents");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.pfm"});
  // A real writer over an existing file.
  writePfm(target, testImage(2, 2));
  EXPECT_EQ(readPfm(target).rgb, testImage(2, 2).rgb);
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.pfm"});
}

TEST(ImageIo, AtomicWriteToMissingDirectory) {
  TempDir dir;
  const std::string target = dir.file("no/such/dir/out.png");
  std::string message = inputError([&] { writePng(target, 1, 1, {1, 2, 3, 4}); });
  EXPECT_TRUE(contains(message, target + ": cannot write")) << message;
  EXPECT_TRUE(dir.entries().empty());
  // A parent that is a file, not a directory.
  writeFile(dir.file("plain"), "x");
  message = inputError([&] { writeExr(dir.file("plain") + "/out.exr", testImage(1, 1)); });
  EXPECT_TRUE(contains(message, dir.file("plain") + "/out.exr: cannot write")) << message;
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"plain"});
}

TEST(ImageIo, AtomicWriteOntoDirectory) {
  TempDir dir;
  fs::create_directory(dir.path() / "sub");
  std::string message = inputError([&] { writePfm(dir.file("sub"), testImage(1, 1)); });
  EXPECT_TRUE(contains(message, dir.file("sub") + ": cannot write: it is a directory")) << message;
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"sub"});
}

TEST(ImageIo, AtomicWriteToUnwritableDirectory) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes anywhere";
  TempDir dir;
  fs::create_directory(dir.path() / "ro");
  fs::permissions(dir.path() / "ro", fs::perms::owner_read | fs::perms::owner_exec);
  std::string target = (dir.path() / "ro" / "x.png").string();
  std::string message = inputError([&] { writePng(target, 1, 1, {1, 2, 3, 4}); });
  fs::permissions(dir.path() / "ro", fs::perms::owner_all);
  EXPECT_TRUE(contains(message, target + ": cannot write in directory")) << message;
  EXPECT_TRUE(fs::is_empty(dir.path() / "ro"));
}

}  // namespace
}  // namespace ferry
