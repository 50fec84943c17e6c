// `ferry info`: what a scene holds and what it would cost in memory.
#pragma once

#include <string>

namespace CLI {
class App;
}

namespace ferry {

struct InfoOptions {
  std::string scene = "builtin:island";
  bool json = false;
  bool envFallback = false;  // --env-fallback, as for render
  // --volume-bricks, as for render: the scene described as a render holds it.
  std::string volumeBricks = "auto";
};

void addInfoCommand(CLI::App& app, InfoOptions& options);
int runInfo(const InfoOptions& options);

}  // namespace ferry
