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
  if (format_ == ImageFormat::Png && !image.aovs.empty())
    throw InputError(fmt::format("{}: a PNG holds no AOVs", path_));
  // The AOVs' channels apart, one ImageChannel each (none without --aov).
  const size_t pixels = size_t(image.width) * size_t(image.height);
  const size_t stride = size_t(aovChannelCount(image.aovs));
  std::vector<ImageChannel> channels;
  for (Aov aov : image.aovs) {
    const AovSpec& spec = aovSpec(aov);
    for (int k = 0; k < spec.channels; ++k) {
      ImageChannel& c = channels.emplace_back();
      c.name = spec.channelNames[size_t(k)];
      c.values.resize(pixels);
      const size_t offset = channels.size() - 1;
      for (size_t i = 0; i < pixels; ++i) c.values[i] = image.aovValues[i * stride + offset];
    }
  }
  switch (format_) {
    case ImageFormat::Png:
      writePng(path_, image.width, image.height, image.rgba);
      return;
    case ImageFormat::Exr:
      writeExr(path_, {image.width, image.height, image.linear}, channels);
      return;
    case ImageFormat::Pfm: {
      writePfm(path_, {image.width, image.height, image.linear});
      // Each AOV beside it, as the library writes them (api::writeImage).
      size_t channel = 0;
      for (Aov aov : image.aovs) {
        const AovSpec& spec = aovSpec(aov);
        const int stored = spec.channels == 1 ? 1 : 3;
        std::vector<float> values(pixels * size_t(stored), 0.0f);
        for (size_t i = 0; i < pixels; ++i)
          for (size_t k = 0; k < size_t(spec.channels); ++k)
            values[i * size_t(stored) + k] = channels[channel + k].values[i];
        channel += size_t(spec.channels);
        writePfm(sideFilePath(path_, spec.name), image.width, image.height, stored, values);
      }
      return;
    }
  }
}

}  // namespace ferry
