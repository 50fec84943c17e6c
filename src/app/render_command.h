// `ferry render`: load a scene, render it, write the image and the stats.
#pragma once

#include "flags/render_flags.h"

namespace CLI {
class App;
}

namespace ferry {

class Communicator;

void addRenderCommand(CLI::App& app, RenderOptions& options);
// Renders on every rank of `comm` through the library (include/ferry/ferry.h:
// the command is one of its clients); returns this rank's exit code. Errors
// every rank meets while setting up are agreed on and reported once; an
// error on one rank while rendering ends all ranks (see Communicator).
int runRender(const RenderOptions& options, const Communicator& comm);

}  // namespace ferry
