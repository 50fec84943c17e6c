// `ferry view`'s HTTP server on rank 0 (cpp-httplib, only here): serves the
// page, the accumulated image and the stats, and turns the API's requests
// into the ViewChanges the session applies at the next frame boundary
// (docs/viewer.md, "API"):
//
//   GET  /            the page (viewer_page.h)
//   GET  /frame.png   the image, tone mapped (?after=ID: waits up to 2 s for a newer frame)
//   GET  /stats       JSON: frames, camera, settings, views, stats, colour maps
//   POST /camera      {"from":[x,y,z],"at":[x,y,z],"up":[x,y,z],"fov":deg}
//   POST /settings    {"width","height","spp","max_depth","exposure","view","field",...}
//   POST /quit        ends every rank at the next frame boundary
// Requests are checked (view_requests.h): a bad one gets a 4xx with the
// reason and changes nothing. The server runs on its own threads; the render
// loop only takes changes and publishes frames, under one mutex.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "scene/scene.h"
#include "session/render_session.h"
#include "viewer/view_requests.h"

namespace ferry {

class ViewerServer final : public InteractiveControl {
 public:
  // Listens on `bind`:`port` (0: any free port); throws InputError if it
  // cannot. `views` are the scene's named views; `initial` the first camera
  // and settings (answered by /stats before the first frame).
  ViewerServer(const std::string& bind, int port, std::vector<CameraView> views,
               const CameraView& initial, const RenderSettings& settings, int ranks,
               ViewLimits limits = {});
  ~ViewerServer() override;
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  int port() const;
  std::string url() const;
  // Ends the session at the next frame boundary (POST /quit, Ctrl-C).
  void requestQuit();
  // The scene was read again for another field: its arrays and the one shown.
  void setFields(std::vector<VolumeField> fields, int32_t field);

  ViewChange takeChange() override;
  bool restartPending() override;
  void publish(const InteractiveFrame& frame) override;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Makes SIGINT and SIGTERM (what mpirun sends every rank on Ctrl-C) ask the
// viewer to quit at the next frame boundary instead of killing the process;
// rank 0's takeChange() passes it on to every rank. A second signal kills.
void quitOnSignals();

}  // namespace ferry
