// Where a render session's images go. The session composites the ranks'
// partial frame buffers (a collective) only when a sink wants an image, in
// the form it wants, and hands it over on rank 0.
//
// A file writer wants only the final image; an interactive viewer wants the
// accumulated image after every frame. Compositing is collective, so every
// rank's sink must answer frames() and pixels() alike (each rank makes the
// same sink from the same settings); only rank 0's receives images.
#pragma once

#include <cstdint>
#include <vector>

#include "core/math.h"
#include "render/aov.h"

namespace ferry {

// The frames accumulated so far, averaged: frames 0..frame, samplesPerPixel each.
struct FrameImage {
  int frame = 0;      // the last frame accumulated (0-based)
  bool last = false;  // the session's final image: no more frames follow
  int width = 0;
  int height = 0;
  std::vector<Vec3f> linear;  // FrameSink::Pixels::Linear: average radiance, row 0 at the top
  std::vector<uint8_t> rgba;  // FrameSink::Pixels::ToneMapped: RGBA8 by the session's tone mapping
  // With --aov: the AOVs, and with Pixels::Linear their averages,
  // aovChannelCount(aovs) floats a pixel (the AOVs in order, each its
  // channels), row 0 at the top.
  std::vector<Aov> aovs;
  std::vector<float> aovValues;
};

class FrameSink {
 public:
  enum class Frames {
    Last,  // the final image only
    Every  // the accumulated image after every frame (progressive)
  };
  enum class Pixels { Linear, ToneMapped };

  virtual ~FrameSink() = default;
  virtual Frames frames() const = 0;
  virtual Pixels pixels() const = 0;
  // Rank 0 only. The final image comes after every collective of the session:
  // what it throws ends only rank 0's run (the other ranks have finished).
  // An earlier image comes between frames, while the other ranks go on: what
  // its receive() throws ends every rank (Communicator::abortAll).
  virtual void receive(const FrameImage& image) = 0;
};

}  // namespace ferry
