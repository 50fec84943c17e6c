// `ferry render`: load a scene, render it, write the image and the stats.
#pragma once

#include <cstdint>
#include <string>

namespace CLI {
class App;
}

namespace ferry {

struct RenderOptions {
  std::string scene = "builtin:island";
  std::string size = "1280x720";
  int samplesPerPixel = 1;
  int frames = 1;
  int maxDepth = 5;
  std::string view;
  uint32_t seed = 1;
  int threads = 0;
  std::string output = "ferry.png";
  std::string statsPath;
  float exposure = 0;
  bool quiet = false;
};

void addRenderCommand(CLI::App& app, RenderOptions& options);
// Returns the process exit code; throws InputError for bad input.
int runRender(const RenderOptions& options);

// "1280x720" -> (1280, 720); throws InputError naming the flag.
void parseImageSize(const std::string& text, int& width, int& height);

}  // namespace ferry
