#include "session/image_file_sink.h"

#include <filesystem>

#include <fmt/format.h>

#include "core/error.h"

namespace ferry {

void checkOutputPath(const std::string& path) {
  if (!imageFormatOf(path))
    throw InputError(fmt::format("-o {}: unknown image format '{}' (use .png, .exr or .pfm)", path,
                                 lowerCaseExtension(path)));
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw InputError(fmt::format("-o {}: directory '{}' does not exist", path, dir.string()));
}

ImageFileSink::ImageFileSink(std::string path) : path_(std::move(path)) {
  checkOutputPath(path_);
  format_ = *imageFormatOf(path_);
}

FrameSink::Pixels ImageFileSink::pixels() const {
  return format_ == ImageFormat::Png ? Pixels::ToneMapped : Pixels::Linear;
}

void ImageFileSink::receive(const FrameImage& image) {
  if (!image.last) return;
  switch (format_) {
    case ImageFormat::Png:
      writePng(path_, image.width, image.height, image.rgba);
      return;
    case ImageFormat::Exr:
      writeExr(path_, {image.width, image.height, image.linear});
      return;
    case ImageFormat::Pfm:
      writePfm(path_, {image.width, image.height, image.linear});
      return;
  }
}

}  // namespace ferry
