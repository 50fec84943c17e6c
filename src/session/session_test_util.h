// Helpers for tests that run whole sessions: the final linear image of a
// session on one communicator, or on `ranks` in-process ranks (rank 0's).
#pragma once

#include <vector>

#include "comm/in_process_communicator.h"
#include "session/render_session.h"

namespace ferry::testing {

// The last frame's linear image (rank 0's; empty on the other ranks).
inline std::vector<Vec3f> renderLinear(const Scene& scene, const SessionSettings& settings,
                                       const Communicator& comm) {
  RenderSession session(scene, settings, comm);
  struct Sink final : FrameSink {
    Frames frames() const override { return Frames::Last; }
    Pixels pixels() const override { return Pixels::Linear; }
    void receive(const FrameImage& image) override { linear = image.linear; }
    std::vector<Vec3f> linear;
  } sink;
  session.run(sink);
  return sink.linear;
}

// The same on `ranks` in-process ranks.
inline std::vector<Vec3f> renderOnRanks(const Scene& scene, const SessionSettings& settings,
                                        int ranks) {
  std::vector<Vec3f> image;
  runRanks(ranks, [&](const Communicator& comm) {
    std::vector<Vec3f> mine = renderLinear(scene, settings, comm);
    if (comm.isRoot()) image = std::move(mine);
  });
  return image;
}

}  // namespace ferry::testing
