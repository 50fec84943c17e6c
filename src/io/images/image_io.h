// Reading textures and environment images, and writing rendered images.
// Every writer goes to a temporary file next to the target and renames it, so
// a failed or interrupted write never replaces a good image with half of one.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/math.h"
#include "scene/texture.h"

namespace ferry {

// The formats Ferry writes rendered images in: PNG (tone mapped, 8 bits), EXR
// and PFM (linear radiance).
enum class ImageFormat { Png, Exr, Pfm };
// The written format a file name asks for, by its extension (case-insensitive:
// "a.PNG" is a PNG); nullopt for any other extension, or none.
std::optional<ImageFormat> imageFormatOf(const std::string& path);
// The extension of `path` in lower case, with its dot (".png"; empty if none):
// what error messages about a format quote.
std::string lowerCaseExtension(const std::string& path);

// 8-bit images (PNG, JPEG, TGA, BMP) as RGBA; throws InputError naming the file.
// Sizes are checked from the header before decoding: over 2^28 pixels, or more
// pixels than any encoding could pack into the file's size, is an InputError.
Texture readTexture(const std::string& path);
// An 8-bit image used as a cut-out mask (MTL map_d): the file's alpha channel
// when it has one, else its grey value (luma of the encoded RGB) moved into alpha.
Texture readAlphaTexture(const std::string& path);
// HDR images (EXR, HDR, PFM) and 8-bit ones (converted to linear) as float RGB.
// Chosen by extension. Non-finite pixels are an InputError; negative ones are
// clamped to zero (they are filter ringing, and radiance cannot be negative).
// EXR: any channels RgbaInputFile understands (RGB, RGBA, Y...), any data
// window; reading sets OpenEXR's process-wide maximum image and tile size to
// 65536 so that a damaged header cannot make it allocate gigabytes.
HdrImage readHdrImage(const std::string& path);

// `rgb` is width*height linear RGB, row 0 at the top.
// PNG: tone mapped by `toPng`; EXR (half float) and PFM: linear. Chosen by extension;
// throws InputError for an unknown extension.
struct LinearImage {
  int width = 0;
  int height = 0;
  std::vector<Vec3f> rgb;
};
void writePng(const std::string& path, int width, int height, const std::vector<uint8_t>& rgba);
// The same PNG in memory (the viewer serves it).
std::string encodePng(int width, int height, const std::vector<uint8_t>& rgba);
// Half-float RGB, ZIP compressed, rounded as core/half.h does (saturating at 65504).
void writeExr(const std::string& path, const LinearImage& image);
// A file beside `path` tagged `tag`: "out/a.pfm", "albedo" -> "out/a.albedo.pfm".
std::string sideFilePath(const std::string& path, const std::string& tag);
// A named channel of floats beside an image's colour, one a pixel, row 0 at
// the top (the AOVs: render/aov.h).
struct ImageChannel {
  std::string name;
  std::vector<float> values;
};
// The colour as writeExr(path, image) rounds it (R, G, B; no alpha), and
// `extra` as 32-bit float channels of the same file; with no extra channel,
// exactly writeExr(path, image).
void writeExr(const std::string& path, const LinearImage& image,
              const std::vector<ImageChannel>& extra);
// "PF", little-endian (scale -1), rows bottom to top as the format says.
void writePfm(const std::string& path, const LinearImage& image);
// The same for `channels` (1: "Pf", grey; 3: "PF") floats a pixel, row 0 at the top.
void writePfm(const std::string& path, int width, int height, int channels,
              const std::vector<float>& values);
// "PF" (RGB) or "Pf" (grey, replicated to RGB), either byte order; the scale's
// magnitude is ignored. The file size must match the header exactly (checked
// before allocating). Values are returned as stored, non-finite ones included.
LinearImage readPfm(const std::string& path);

// The PNG encoding of a linear image: clamped to [0, 1], sRGB-encoded, rounded
// to 8 bits, alpha 255. No exposure: scale the image first if needed.
std::vector<uint8_t> toPng(const LinearImage& image);
// Writes .png (through toPng), .exr or .pfm, chosen by imageFormatOf(path).
void writeImage(const std::string& path, const LinearImage& image);

// Runs `write(tempPath)` and renames the result onto `path`; removes the
// temporary on failure. Throws InputError if the directory is not writable.
// The temporary is ".NAME.tmp.PID.N" in the target's directory (so the rename is
// atomic), created before `write` runs, and fsync'ed before the rename. Whatever
// `write` throws is rethrown after the cleanup; the target is then untouched.
void writeFileAtomically(const std::string& path,
                         const std::function<void(const std::string&)>& write);

}  // namespace ferry
