#include "app/view_command.h"

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <span>
#include <string>

#include "app/progress.h"
#include "comm/communicator.h"
#include "core/error.h"
#include "session/render_session.h"
#include "session/session_stats.h"
#include "viewer/viewer_server.h"

namespace ferry {

void addViewCommand(CLI::App& app, ViewOptions& o) {
  CLI::App* view = app.add_subcommand(
      "view",
      "Render a scene interactively in the browser: every rank renders progressively, rank 0\n"
      "serves the image, the controls and live stats. Prints the URL. On a cluster, reach the\n"
      "head node's port through an SSH tunnel:\n"
      "  mpirun -np 4 ferry view builtin:island --port 8080\n"
      "  ssh -L 8080:localhost:8080 head-node     (then open http://localhost:8080/)\n"
      "API: GET / (the page), GET /frame.png, GET /stats (JSON), POST /camera\n"
      "{\"from\":[x,y,z],\"at\":[x,y,z],\"up\":[x,y,z],\"fov\":deg}, POST /settings "
      "{\"width\",\"height\",\n"
      "\"spp\",\"max_depth\",\"exposure\",\"view\",\"display\",\"field\"}, POST /quit. Ctrl-C also "
      "quits.");
  o.render.size = "640x360";
  o.render.writesImage = false;
  addRenderingOptions(view, o.render);
  view->add_option("--aov", o.render.aov,
                   "AOVs the page (and POST /settings {\"display\":NAME}) can show instead of the\n"
                   "colour: a comma list of albedo, normal, geometric-normal, depth, position, uv");
  view->add_option("--port", o.port, "Port of the HTTP server on rank 0 (0: any free port)")
      ->capture_default_str();
  view->add_option("--bind", o.bind,
                   "Address it listens on: 127.0.0.1 (this machine only) unless you say\n"
                   "otherwise, e.g. 0.0.0.0 for every interface")
      ->capture_default_str();
  view->add_option("--frames", o.frames, "Stop after this many frames (0: when asked to quit)")
      ->capture_default_str();
}

int runView(const ViewOptions& o, const Communicator& comm) {
  std::optional<RenderSession> session;
  std::optional<ViewerServer> server;
  std::string error;
  SessionSettings settings;
  const bool talk = comm.isRoot() && !o.render.quiet;
  // Reads the scene (again, for another field) into `session`.
  auto load = [&] {
    Progress loading("load", 1, talk);
    loading.update(0, o.render.scene);
    session.emplace(settings, comm);
    loading.finish(setupIntervalsText(session->setupTimes(), "agree") + " s");
  };
  try {
    settings = sessionSettings(o.render, comm);
    load();
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (comm.agreeOnFailure(!error.empty(), error)) return 1;
  // The look controls when any rank holds a volume they restyle (bricks may be elsewhere).
  const bool looks = comm.sum(uint64_t(session->hasTransferFunctionVolumes())) > 0;
  try {
    if (comm.isRoot()) {
      const Scene& scene = session->scene();
      const RenderSettings& r = session->settings().render;
      ViewLimits limits;
      limits.volumeLook = looks;
      limits.aovs = r.aovs;
      limits.fields = scene.volumeFields;
      limits.field = scene.volumeField;
      server.emplace(o.bind, o.port, scene.views, r.camera ? *r.camera : scene.view(r.view), r,
                     comm.size(), limits);
    }
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (comm.agreeOnFailure(!error.empty(), error)) return 1;

  quitOnSignals();
  if (comm.isRoot()) {
    fmt::print("ferry view: {} ({} rank{}; POST /quit or Ctrl-C to stop)\n", server->url(),
               comm.size(), comm.size() == 1 ? "" : "s");
    std::fflush(stdout);
  }
  uint64_t frames = 0;
  for (;;) {
    InteractiveEnd end;
    try {
      end = session->runInteractive(server ? &*server : nullptr,
                                    o.frames > 0 ? o.frames - std::min(frames, o.frames) : 0);
    } catch (const std::exception& e) {
      comm.abortAll(e.what());
    }
    frames += end.frames;
    if (end.field < 0 || (o.frames > 0 && frames >= o.frames)) break;
    // Another array of the VTK data: the scene is read again rendering it,
    // from the view and settings the session had.
    // Rank 0's scene names it (a rank of a .pvtu may hold no piece).
    std::string field =
        comm.isRoot() ? session->scene().volumeFields.at(size_t(end.field)).name : std::string();
    uint64_t length = field.size();
    comm.broadcast(length);
    field.resize(length);
    comm.broadcast(std::span<char>(field.data(), field.size()));
    if (talk)
      fmt::print("ferry view: reading {} again for its field '{}'\n", o.render.scene, field);
    settings.load.field = field;
    settings.render = end.render;
    settings.render.camera = end.camera;
    session.reset();  // the old scene's memory first
    try {
      load();
    } catch (const std::exception& e) {
      error = e.what();
    }
    if (comm.agreeOnFailure(!error.empty(), error)) return 1;
    if (server) server->setFields(session->scene().volumeFields, session->scene().volumeField);
  }
  if (comm.isRoot() && !o.render.quiet) fmt::print("ferry view: stopped\n");
  return 0;
}

}  // namespace ferry
