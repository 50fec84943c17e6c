#include "app/image_output.h"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "core/error.h"
#include "io/image_io.h"

namespace ferry {
namespace {

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

void checkOutputPath(const std::string& path) {
  std::string ext = extensionOf(path);
  if (ext != ".png" && ext != ".exr" && ext != ".pfm")
    throw InputError(
        fmt::format("-o {}: unknown image format '{}' (use .png, .exr or .pfm)", path, ext));
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw InputError(fmt::format("-o {}: directory '{}' does not exist", path, dir.string()));
}

void writeRenderedImage(const std::string& path, int width, int height,
                        const std::vector<Vec3f>& linear, const ToneMapping& toneMapping) {
  std::string ext = extensionOf(path);
  if (ext == ".png") {
    writePng(path, width, height, toneMapToRgba8(linear, toneMapping));
  } else {
    LinearImage image{width, height, linear};
    if (ext == ".exr")
      writeExr(path, image);
    else
      writePfm(path, image);
  }
}

}  // namespace ferry
