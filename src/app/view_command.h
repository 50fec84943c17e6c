// `ferry view`: interactive, progressive rendering in the browser. Every rank
// renders frame after frame, accumulating; rank 0 serves the page, the
// image and the stats over HTTP (src/viewer) and broadcasts camera and
// settings changes at frame boundaries.
#pragma once

#include <cstdint>
#include <string>

#include "flags/render_flags.h"

namespace CLI {
class App;
}

namespace ferry {

class Communicator;

struct ViewOptions {
  RenderOptions render;  // the scene and how it is rendered (render's options)
  std::string bind = "127.0.0.1";
  int port = 8080;
  uint64_t frames = 0;  // stop after this many frames (0: when asked to quit)
};

void addViewCommand(CLI::App& app, ViewOptions& options);
int runView(const ViewOptions& options, const Communicator& comm);

}  // namespace ferry
