#include "io/images/image_io.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include <ImfArray.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <fmt/format.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include "core/error.h"
#include "core/half.h"

namespace ferry {
namespace {

namespace fs = std::filesystem;

// No image Ferry reads is anywhere near this; a header claiming more is broken
// or hostile, and believing it would mean allocating gigabytes.
constexpr uint64_t kMaxImagePixels = uint64_t(1) << 28;
constexpr int kMaxImageSide = 1 << 24;
// The densest legal encoding stb decodes (a 1-bit PNG under deflate, ~1032:1)
// yields about 8300 pixels per byte of file. A header promising more pixels
// than that, for the file's size, describes data that is not there.
constexpr uint64_t kMaxPixelsPerFileByte = 8300;

}  // namespace

std::string lowerCaseExtension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::optional<ImageFormat> imageFormatOf(const std::string& path) {
  const std::string ext = lowerCaseExtension(path);
  if (ext == ".png") return ImageFormat::Png;
  if (ext == ".exr") return ImageFormat::Exr;
  if (ext == ".pfm") return ImageFormat::Pfm;
  return std::nullopt;
}

namespace {

// The size of a readable regular file; InputError otherwise.
uint64_t requireRegularFile(const std::string& path) {
  std::error_code ec;
  fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw InputError(fmt::format("{}: no such file", path));
  if (!fs::is_regular_file(status)) throw InputError(fmt::format("{}: not a regular file", path));
  uint64_t size = fs::file_size(path, ec);
  if (ec) throw InputError(fmt::format("{}: cannot read: {}", path, ec.message()));
  return size;
}

void checkDimensions(const std::string& path, uint64_t width, uint64_t height) {
  if (width == 0 || height == 0)
    throw InputError(fmt::format("{}: image has no pixels ({}x{})", path, width, height));
  if (width > uint64_t(kMaxImageSide) || height > uint64_t(kMaxImageSide) ||
      width * height > kMaxImagePixels)
    throw InputError(
        fmt::format("{}: image of {}x{} pixels is larger than Ferry accepts ({} pixels)", path,
                    width, height, kMaxImagePixels));
}

struct StbInfo {
  int width = 0, height = 0, channels = 0;
};

// Reads the header only, so sizes are checked before stb allocates anything.
// stb tries every format in turn, so a PNG with a bad header reports
// "unknown image type"; the signature tells what the file meant to be.
std::string whyNotReadable(const std::string& path, uint64_t fileSize) {
  if (fileSize == 0) return "empty file";
  std::string reason = stbi_failure_reason() ? stbi_failure_reason() : "unknown error";
  if (reason != "unknown image type") return reason;
  unsigned char head[8] = {};
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  size_t n = file ? std::fread(head, 1, sizeof(head), file.get()) : 0;
  if (n >= 8 && std::memcmp(head, "\x89PNG\r\n\x1a\n", 8) == 0)
    return "corrupt, unsupported or too large PNG header";
  if (n >= 3 && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF)
    return "corrupt, unsupported or too large JPEG header";
  if (n >= 2 && head[0] == 'B' && head[1] == 'M')
    return "corrupt, unsupported or too large BMP header";
  return reason;
}

StbInfo stbInfo(const std::string& path) {
  uint64_t fileSize = requireRegularFile(path);
  StbInfo info;
  if (!stbi_info(path.c_str(), &info.width, &info.height, &info.channels))
    throw InputError(
        fmt::format("{}: cannot read image: {}", path, whyNotReadable(path, fileSize)));
  checkDimensions(path, uint64_t(info.width), uint64_t(info.height));
  uint64_t pixels = uint64_t(info.width) * uint64_t(info.height);
  if (pixels > std::max<uint64_t>(fileSize, 1024) * kMaxPixelsPerFileByte)
    throw InputError(fmt::format(
        "{}: header claims {}x{} pixels, impossible for a file of {} bytes (truncated or corrupt)",
        path, info.width, info.height, fileSize));
  return info;
}

struct StbFree {
  void operator()(void* p) const { stbi_image_free(p); }
};

Texture loadRgba8(const std::string& path, int* channelsInFile) {
  StbInfo info = stbInfo(path);
  int w = 0, h = 0, n = 0;
  std::unique_ptr<stbi_uc, StbFree> data(stbi_load(path.c_str(), &w, &h, &n, 4));
  if (!data)
    throw InputError(fmt::format("{}: cannot decode image: {} (corrupt or truncated file?)", path,
                                 stbi_failure_reason()));
  if (w != info.width || h != info.height)
    throw InputError(fmt::format("{}: image size changed while reading", path));
  Texture texture;
  texture.name = path;
  texture.width = w;
  texture.height = h;
  texture.rgba.assign(data.get(), data.get() + size_t(w) * size_t(h) * 4);
  if (channelsInFile) *channelsInFile = n;
  return texture;
}

void requireFinite(const std::string& path, const HdrImage& image) {
  for (size_t i = 0; i < image.pixels.size(); ++i)
    if (!isFinite(image.pixels[i]))
      throw InputError(fmt::format("{}: pixel ({}, {}) is not finite", path,
                                   i % size_t(image.width), i / size_t(image.width)));
}

void clampNegative(HdrImage& image) {
  for (Vec3f& p : image.pixels) p = max(p, Vec3f(0));
}

// OpenEXR sizes its line-offset table and line buffers from the header, before
// Ferry sees it; these process-wide limits make it reject absurd headers itself.
constexpr int kMaxExrSide = 1 << 16;

void limitExrSizes() {
  static const bool once = [] {
    Imf::Header::setMaxImageSize(kMaxExrSide, kMaxExrSide);
    Imf::Header::setMaxTileSize(kMaxExrSide, kMaxExrSide);
    return true;
  }();
  (void)once;
}

HdrImage readExr(const std::string& path) {
  requireRegularFile(path);
  limitExrSizes();
  HdrImage image;
  image.name = path;
  try {
    Imf::RgbaInputFile file(path.c_str());
    const Imath::Box2i dw = file.dataWindow();
    const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
    const int64_t height = int64_t(dw.max.y) - dw.min.y + 1;
    if (width <= 0 || height <= 0) throw InputError(fmt::format("{}: empty data window", path));
    checkDimensions(path, uint64_t(width), uint64_t(height));
    image.width = int(width);
    image.height = int(height);
    // Read in bands and grow the result as rows actually decode: a header that
    // lies about the size fails on the first missing band, not after a huge
    // allocation.
    constexpr int64_t kBandRows = 64;
    std::vector<Imf::Rgba> band(size_t(width * std::min(height, kBandRows)));
    for (int64_t y0 = 0; y0 < height; y0 += kBandRows) {
      int64_t rows = std::min(kBandRows, height - y0);
      // OpenEXR addresses the frame buffer with absolute data-window coordinates.
      Imf::Rgba* base = band.data() - (int64_t(dw.min.x) + (int64_t(dw.min.y) + y0) * width);
      file.setFrameBuffer(base, 1, size_t(width));
      file.readPixels(int(dw.min.y + y0), int(dw.min.y + y0 + rows - 1));
      for (int64_t i = 0; i < rows * width; ++i)
        image.pixels.push_back(
            {float(band[size_t(i)].r), float(band[size_t(i)].g), float(band[size_t(i)].b)});
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: cannot read EXR: {}", path, e.what()));
  }
  return image;
}

HdrImage readRadianceHdr(const std::string& path) {
  StbInfo info = stbInfo(path);
  if (!stbi_is_hdr(path.c_str()))
    throw InputError(fmt::format("{}: not a Radiance HDR file", path));
  int w = 0, h = 0, n = 0;
  std::unique_ptr<float, StbFree> data(stbi_loadf(path.c_str(), &w, &h, &n, 3));
  if (!data)
    throw InputError(fmt::format("{}: cannot read image: {}", path, stbi_failure_reason()));
  if (w != info.width || h != info.height)
    throw InputError(fmt::format("{}: image size changed while reading", path));
  HdrImage image;
  image.name = path;
  image.width = w;
  image.height = h;
  image.pixels.resize(size_t(w) * size_t(h));
  const float* p = data.get();
  for (size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
  return image;
}

void checkImage(const char* what, int width, int height, size_t values, size_t valuesPerPixel) {
  FERRY_CHECK_GT(width, 0);
  FERRY_CHECK_GT(height, 0);
  if (values != size_t(width) * size_t(height) * valuesPerPixel)
    throw InternalError(fmt::format("{}: {} values for a {}x{} image with {} per pixel", what,
                                    values, width, height, valuesPerPixel));
}

// A file descriptor that closes itself.
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

void syncFile(const fs::path& path, int flags) {
  Fd f{::open(path.c_str(), flags | O_CLOEXEC)};
  if (f.fd >= 0) ::fsync(f.fd);
}

uint32_t byteSwap(uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

}  // namespace

Texture readTexture(const std::string& path) {
  return loadRgba8(path, nullptr);
}

Texture readAlphaTexture(const std::string& path) {
  int channels = 0;
  Texture texture = loadRgba8(path, &channels);
  // 1: grey, 2: grey + alpha, 3: RGB, 4: RGBA. Without an alpha channel the
  // mask is the grey level (coverage is linear, so the bytes are used as they are).
  if (channels == 1 || channels == 3) {
    for (size_t i = 0; i < texture.rgba.size(); i += 4) {
      const uint8_t* p = &texture.rgba[i];
      texture.rgba[i + 3] = uint8_t(std::lround(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]));
    }
  }
  texture.srgb = false;
  return texture;
}

HdrImage readHdrImage(const std::string& path) {
  std::string ext = lowerCaseExtension(path);
  HdrImage image;
  if (ext == ".exr") {
    image = readExr(path);
  } else if (ext == ".hdr") {
    image = readRadianceHdr(path);
  } else if (ext == ".pfm") {
    LinearImage pfm = readPfm(path);
    image.name = path;
    image.width = pfm.width;
    image.height = pfm.height;
    image.pixels = std::move(pfm.rgb);
  } else if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tga" || ext == ".bmp") {
    Texture texture = readTexture(path);
    image.name = path;
    image.width = texture.width;
    image.height = texture.height;
    image.pixels.resize(texture.texelCount());
    for (size_t i = 0; i < image.pixels.size(); ++i) {
      const uint8_t* p = &texture.rgba[4 * i];
      image.pixels[i] = {srgbToLinear(p[0] / 255.0f), srgbToLinear(p[1] / 255.0f),
                         srgbToLinear(p[2] / 255.0f)};
    }
  } else {
    throw InputError(fmt::format(
        "{}: unsupported image format '{}' (supported: .exr, .hdr, .pfm, .png, .jpg, .tga, .bmp)",
        path, ext));
  }
  requireFinite(path, image);
  clampNegative(image);
  return image;
}

void writePng(const std::string& path, int width, int height, const std::vector<uint8_t>& rgba) {
  checkImage("writePng", width, height, rgba.size(), 4);
  writeFileAtomically(path, [&](const std::string& temp) {
    if (!stbi_write_png(temp.c_str(), width, height, 4, rgba.data(), width * 4))
      throw InputError(fmt::format("{}: cannot write PNG", path));
  });
}

std::string encodePng(int width, int height, const std::vector<uint8_t>& rgba) {
  checkImage("encodePng", width, height, rgba.size(), 4);
  std::string out;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size_t(size));
  };
  if (!stbi_write_png_to_func(append, &out, width, height, 4, rgba.data(), width * 4))
    throw std::runtime_error("cannot encode PNG");
  return out;
}

void writeExr(const std::string& path, const LinearImage& image) {
  checkImage("writeExr", image.width, image.height, image.rgb.size(), 1);
  // Ferry's own rounding, which saturates instead of overflowing to infinity.
  std::vector<Imf::Rgba> pixels(image.rgb.size());
  for (size_t i = 0; i < pixels.size(); ++i) {
    pixels[i].r.setBits(floatToHalf(image.rgb[i].x));
    pixels[i].g.setBits(floatToHalf(image.rgb[i].y));
    pixels[i].b.setBits(floatToHalf(image.rgb[i].z));
    pixels[i].a = 1.0f;
  }
  writeFileAtomically(path, [&](const std::string& temp) {
    try {
      Imf::Header header(image.width, image.height);
      header.compression() = Imf::ZIP_COMPRESSION;
      Imf::RgbaOutputFile file(temp.c_str(), header, Imf::WRITE_RGB);
      file.setFrameBuffer(pixels.data(), 1, size_t(image.width));
      file.writePixels(image.height);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(fmt::format("{}: cannot write EXR: {}", path, e.what()));
    }
  });
}

std::string sideFilePath(const std::string& path, const std::string& tag) {
  const fs::path p(path);
  fs::path side = p;
  side.replace_filename(p.stem().string() + "." + tag + p.extension().string());
  return side.string();
}

void writeExr(const std::string& path, const LinearImage& image,
              const std::vector<ImageChannel>& extra) {
  if (extra.empty()) return writeExr(path, image);
  checkImage("writeExr", image.width, image.height, image.rgb.size(), 1);
  for (const ImageChannel& c : extra)
    checkImage("writeExr", image.width, image.height, c.values.size(), 1);
  // The colour as writeExr(path, image) rounds it, without alpha.
  const size_t pixels = image.rgb.size();
  std::vector<uint16_t> halves(pixels * 3);
  for (size_t i = 0; i < pixels; ++i) {
    halves[3 * i] = floatToHalf(image.rgb[i].x);
    halves[3 * i + 1] = floatToHalf(image.rgb[i].y);
    halves[3 * i + 2] = floatToHalf(image.rgb[i].z);
  }
  writeFileAtomically(path, [&](const std::string& temp) {
    try {
      Imf::Header header(image.width, image.height);
      header.compression() = Imf::ZIP_COMPRESSION;
      Imf::FrameBuffer frame;
      const size_t halfRow = sizeof(uint16_t) * 3 * size_t(image.width);
      const char* names[] = {"R", "G", "B"};
      for (int k = 0; k < 3; ++k) {
        header.channels().insert(names[k], Imf::Channel(Imf::HALF));
        frame.insert(names[k], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(halves.data() + k),
                                          3 * sizeof(uint16_t), halfRow));
      }
      for (const ImageChannel& c : extra) {
        header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
        frame.insert(c.name,
                     Imf::Slice(Imf::FLOAT,
                                const_cast<char*>(reinterpret_cast<const char*>(c.values.data())),
                                sizeof(float), sizeof(float) * size_t(image.width)));
      }
      Imf::OutputFile file(temp.c_str(), header);
      file.setFrameBuffer(frame);
      file.writePixels(image.height);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(fmt::format("{}: cannot write EXR: {}", path, e.what()));
    }
  });
}

void writePfm(const std::string& path, const LinearImage& image) {
  checkImage("writePfm", image.width, image.height, image.rgb.size(), 1);
  std::vector<float> values(image.rgb.size() * 3);
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    values[3 * i] = image.rgb[i].x;
    values[3 * i + 1] = image.rgb[i].y;
    values[3 * i + 2] = image.rgb[i].z;
  }
  writePfm(path, image.width, image.height, 3, values);
}

void writePfm(const std::string& path, int width, int height, int channels,
              const std::vector<float>& values) {
  FERRY_CHECK(channels == 1 || channels == 3);
  checkImage("writePfm", width, height, values.size(), size_t(channels));
  writeFileAtomically(path, [&](const std::string& temp) {
    std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(temp.c_str(), "wb"), &std::fclose);
    if (!file) throw InputError(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
    // Negative scale: little-endian samples. Rows go bottom to top.
    std::string header =
        fmt::format("{}\n{} {}\n-1.0\n", channels == 3 ? "PF" : "Pf", width, height);
    bool ok = std::fwrite(header.data(), 1, header.size(), file.get()) == header.size();
    const size_t rowValues = size_t(width) * size_t(channels);
    std::vector<float> row(rowValues);
    for (int y = height - 1; ok && y >= 0; --y) {
      std::copy_n(values.begin() + ptrdiff_t(size_t(y) * rowValues), rowValues, row.begin());
      if constexpr (std::endian::native == std::endian::big) {
        for (float& f : row) f = std::bit_cast<float>(byteSwap(std::bit_cast<uint32_t>(f)));
      }
      ok = std::fwrite(row.data(), sizeof(float), row.size(), file.get()) == row.size();
    }
    if (!ok || std::fclose(file.release()) != 0)
      throw InputError(fmt::format("{}: cannot write: {}", path, std::strerror(errno)));
  });
}

LinearImage readPfm(const std::string& path) {
  const uint64_t fileSize = requireRegularFile(path);
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw InputError(fmt::format("{}: cannot read: {}", path, std::strerror(errno)));
  // The header is three short lines; 256 bytes hold any honest one.
  char head[256];
  const size_t headLen = std::fread(head, 1, sizeof(head), file.get());
  auto bad = [&](const std::string& what) {
    return InputError(fmt::format("{}: not a valid PFM file: {}", path, what));
  };
  if (headLen < 2 || head[0] != 'P' || (head[1] != 'F' && head[1] != 'f'))
    throw bad("it does not start with 'PF' or 'Pf'");
  const int channels = head[1] == 'F' ? 3 : 1;
  size_t pos = 2;
  auto isSpace = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  auto skipSpace = [&] {
    size_t start = pos;
    while (pos < headLen && isSpace(head[pos])) ++pos;
    return pos > start;
  };
  auto token = [&]() {
    size_t start = pos;
    while (pos < headLen && !isSpace(head[pos])) ++pos;
    return std::string_view(head + start, pos - start);
  };
  auto parseSize = [&](const char* what) {
    if (!skipSpace()) throw bad(fmt::format("expected whitespace before the {}", what));
    std::string_view t = token();
    int64_t v = 0;
    auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || end != t.data() + t.size())
      throw bad(fmt::format("the {} '{}' is not an integer", what, t));
    if (v <= 0 || v > kMaxImageSide) throw bad(fmt::format("the {} {} is out of range", what, v));
    return v;
  };
  const int64_t width = parseSize("width");
  const int64_t height = parseSize("height");
  if (!skipSpace()) throw bad("expected whitespace before the scale");
  std::string_view scaleText = token();
  double scale = 0;
  auto [end, ec] = std::from_chars(scaleText.data(), scaleText.data() + scaleText.size(), scale);
  if (scaleText.empty() || ec != std::errc() || end != scaleText.data() + scaleText.size() ||
      !std::isfinite(scale) || scale == 0)
    throw bad(fmt::format("the scale '{}' is not a finite non-zero number", scaleText));
  // Exactly one whitespace character separates the header from the samples.
  if (pos >= headLen || !isSpace(head[pos])) throw bad("the header is not terminated");
  const uint64_t headerSize = pos + 1;
  checkDimensions(path, uint64_t(width), uint64_t(height));
  const uint64_t samples = uint64_t(width) * uint64_t(height) * uint64_t(channels);
  if (fileSize - headerSize != samples * 4)
    throw InputError(fmt::format(
        "{}: PFM header says {}x{} with {} channel(s) ({} bytes of samples) but the file holds {} "
        "bytes after the header",
        path, width, height, channels, samples * 4, fileSize - headerSize));
  if (std::fseek(file.get(), long(headerSize), SEEK_SET) != 0)
    throw InputError(fmt::format("{}: cannot read: {}", path, std::strerror(errno)));
  std::vector<float> data(samples);
  if (std::fread(data.data(), sizeof(float), data.size(), file.get()) != data.size())
    throw InputError(fmt::format("{}: file ended early while reading the samples", path));
  const bool fileLittle = scale < 0;
  const bool nativeLittle = std::endian::native == std::endian::little;
  if (fileLittle != nativeLittle)
    for (float& f : data) f = std::bit_cast<float>(byteSwap(std::bit_cast<uint32_t>(f)));
  // The magnitude of the scale is ignored, as most readers do.
  LinearImage image;
  image.width = int(width);
  image.height = int(height);
  image.rgb.resize(size_t(width) * size_t(height));
  for (int64_t y = 0; y < height; ++y) {
    const float* row = data.data() + size_t(height - 1 - y) * size_t(width) * size_t(channels);
    for (int64_t x = 0; x < width; ++x) {
      const float* s = row + size_t(x) * size_t(channels);
      image.rgb[size_t(y) * size_t(width) + size_t(x)] =
          channels == 3 ? Vec3f{s[0], s[1], s[2]} : Vec3f(s[0]);
    }
  }
  return image;
}

std::vector<uint8_t> toPng(const LinearImage& image) {
  checkImage("toPng", image.width, image.height, image.rgb.size(), 1);
  std::vector<uint8_t> rgba(image.rgb.size() * 4);
  auto encode = [](float v) {
    if (!(v > 0)) return uint8_t(0);  // also NaN
    return uint8_t(std::lround(linearToSrgb(v) * 255.0f));
  };
  for (size_t i = 0; i < image.rgb.size(); ++i) {
    rgba[4 * i] = encode(image.rgb[i].x);
    rgba[4 * i + 1] = encode(image.rgb[i].y);
    rgba[4 * i + 2] = encode(image.rgb[i].z);
    rgba[4 * i + 3] = 255;
  }
  return rgba;
}

void writeImage(const std::string& path, const LinearImage& image) {
  const std::optional<ImageFormat> format = imageFormatOf(path);
  if (!format)
    throw InputError(fmt::format("{}: unsupported output format '{}' (supported: .png, .exr, .pfm)",
                                 path, lowerCaseExtension(path)));
  switch (*format) {
    case ImageFormat::Png:
      writePng(path, image.width, image.height, toPng(image));
      return;
    case ImageFormat::Exr:
      writeExr(path, image);
      return;
    case ImageFormat::Pfm:
      writePfm(path, image);
      return;
  }
}

void writeFileAtomically(const std::string& path,
                         const std::function<void(const std::string&)>& write) {
  const fs::path target(path);
  if (target.filename().empty() || target.filename() == "." || target.filename() == "..")
    throw InputError(fmt::format("{}: not a file name", path));
  fs::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(
        fmt::format("{}: cannot write: directory '{}' does not exist", path, dir.string()));
  if (fs::is_directory(target, ec))
    throw InputError(fmt::format("{}: cannot write: it is a directory", path));

  // Same directory, so the rename is atomic; hidden, and unique per process and call.
  static std::atomic<uint64_t> counter{0};
  fs::path temp;
  for (int attempt = 0;; ++attempt) {
    temp = dir / fmt::format(".{}.tmp.{}.{}", target.filename().string(), ::getpid(), counter++);
    Fd f{::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666)};
    if (f.fd >= 0) break;
    if (errno != EEXIST || attempt > 100)
      throw InputError(fmt::format("{}: cannot write in directory '{}': {}", path, dir.string(),
                                   std::strerror(errno)));
  }
  try {
    write(temp.string());
    if (!fs::is_regular_file(temp, ec))
      throw InternalError(fmt::format("{}: the writer removed its temporary file", path));
    // Data first, then the name: after a crash the target is the old file or the new one.
    syncFile(temp, O_RDONLY);
    fs::rename(temp, target);
    syncFile(dir, O_RDONLY | O_DIRECTORY);
  } catch (const fs::filesystem_error& e) {
    fs::remove(temp, ec);
    throw InputError(fmt::format("{}: cannot write: {}", path, e.code().message()));
  } catch (...) {
    fs::remove(temp, ec);
    throw;
  }
}

}  // namespace ferry
