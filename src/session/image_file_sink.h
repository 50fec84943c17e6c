// The first frame sink: the final image as a file, its format by the
// extension (imageFormatOf: PNG tone mapped; EXR and PFM linear radiance),
// written by rank 0 through a temporary file and a rename. AOVs as the
// library writes them: float channels of an EXR, files beside a PFM
// (NAME.albedo.pfm); a PNG cannot hold them (InputError).
#pragma once

#include <string>

#include "io/images/image_io.h"
#include "session/frame_sink.h"

namespace ferry {

// Throws InputError before any rendering if `path` cannot be written
// (unknown extension, missing directory); names the -o flag.
void checkOutputPath(const std::string& path);

class ImageFileSink final : public FrameSink {
 public:
  // `path` as checkOutputPath accepts.
  explicit ImageFileSink(std::string path);
  Frames frames() const override { return Frames::Last; }
  Pixels pixels() const override;
  void receive(const FrameImage& image) override;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  ImageFormat format_;
};

}  // namespace ferry
