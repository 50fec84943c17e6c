#include "viewer/viewer_server.h"

#include <fmt/format.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <mutex>
#include <thread>
#include <utility>

#include "core/error.h"
#include "io/images/image_io.h"
#include "media/volume_look.h"
#include "viewer/viewer_page.h"

namespace ferry {
namespace {

std::atomic<bool> gQuitSignal{false};

void onQuitSignal(int signal) {
  if (gQuitSignal.exchange(true)) {  // the second one: stop waiting for a frame boundary
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }
}

nlohmann::json vec(Vec3f v) {
  return {v.x, v.y, v.z};
}

nlohmann::json cameraJson(const CameraView& c) {
  return {{"from", vec(c.from)},
          {"at", vec(c.at)},
          {"up", vec(c.up)},
          {"fov", c.fovY},
          {"lens_radius", c.lensRadius},
          {"focal_distance", c.focalDistance}};
}

nlohmann::json settingsJson(const RenderSettings& s) {
  return {{"width", s.width},
          {"height", s.height},
          {"spp", s.samplesPerPixel},
          {"max_depth", s.maxDepth},
          {"exposure", s.toneMapping.exposure},
          {"display", s.toneMapping.aov >= 0 ? aovSpec(Aov(s.toneMapping.aov)).name : "color"},
          {"volume_opacity", s.volumeLook.opacity},
          {"color_map", s.volumeLook.colorMap}};
}

}  // namespace

struct ViewerServer::State {
  httplib::Server server;
  std::thread thread;
  std::string bind;
  int port = 0;
  ViewLimits limits;
  std::vector<CameraView> views;
  int ranks = 1;

  std::mutex mutex;
  std::condition_variable newFrame;
  bool stopping = false;
  // What clients asked for and the loop has not taken yet (flags accumulate;
  // the last value of each field wins), and the state it leads to (what a
  // partial request completes).
  ViewChange pending;
  CameraView requestedCamera;
  RenderSettings requestedSettings;
  // A focus pick was taken: the next published frame's focal distance
  // becomes the requested one (only the session knows what the pick found).
  bool focusTaken = false;
  // A field change was taken: the scene is being read again (-1: none).
  int32_t loadingField = -1;
  // The last published frame.
  std::string png;
  uint64_t frameId = 0;
  uint64_t abandonedTotal = 0;  // frames abandoned for a change (render thread only)
  nlohmann::json stats;

  void routes();
  // Applies a checked request under the lock; 400 with the reason if refused.
  template <typename Apply>
  void change(const std::string& body, httplib::Response& response, Apply&& apply);
};

namespace {

constexpr size_t kMaxBodyBytes = 64 * 1024;  // a camera is a few hundred bytes

// A POST's body, read by its handler; false (the response says why) if it
// could not be read. A POST that says nothing of a body (no Content-Length
// and not chunked, as `curl -X POST` sends it) has an empty one.
bool readBody(const httplib::Request& request, httplib::Response& response,
              const httplib::ContentReader& reader, std::string& body) {
  if (!request.has_header("Content-Length") && !request.has_header("Transfer-Encoding"))
    return true;
  const bool read = reader([&](const char* data, size_t bytes) {
    body.append(data, bytes);
    return true;
  });
  if (read) return true;
  if (response.status == 413)
    response.set_content(fmt::format("{} {}: the body is over the {}-byte limit\n", request.method,
                                     request.path, kMaxBodyBytes),
                         "text/plain");
  else {
    response.status = 400;
    response.set_content(fmt::format("{} {}: the body could not be read (cut short, or a "
                                     "Content-Length that does not match it)\n",
                                     request.method, request.path),
                         "text/plain");
  }
  return false;
}

}  // namespace

template <typename Apply>
void ViewerServer::State::change(const std::string& body, httplib::Response& response,
                                 Apply&& apply) {
  std::lock_guard lock(mutex);
  ViewChange change = pending;
  try {
    apply(body, change);
  } catch (const RequestError& e) {
    response.status = 400;
    response.set_content(nlohmann::json{{"error", e.what()}}.dump(), "application/json");
    return;
  }
  // Accepted: it becomes what the next frame renders.
  pending = change;
  change.applyTo(requestedCamera, requestedSettings);
  response.set_content(nlohmann::json{{"camera", cameraJson(requestedCamera)},
                                      {"settings", settingsJson(requestedSettings)}}
                           .dump(),
                       "application/json");
}

void ViewerServer::State::routes() {
  server.set_payload_max_length(kMaxBodyBytes);
  // SO_REUSEADDR only: httplib's default adds SO_REUSEPORT, which lets a
  // second viewer bind the same port and silently share its connections.
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  server.Get("/", [](const httplib::Request&, httplib::Response& response) {
    response.set_content(viewerPage(), "text/html; charset=utf-8");
  });
  server.Get("/frame.png", [this](const httplib::Request& request, httplib::Response& response) {
    std::unique_lock lock(mutex);
    if (request.has_param("after")) {
      uint64_t after = 0;
      try {
        after = std::stoull(request.get_param_value("after"));
      } catch (const std::exception&) {
        response.status = 400;
        response.set_content("'after' must be a frame id", "text/plain");
        return;
      }
      newFrame.wait_for(lock, std::chrono::seconds(2),
                        [&] { return stopping || frameId != after; });
    } else if (png.empty()) {
      newFrame.wait_for(lock, std::chrono::seconds(2), [&] { return stopping || !png.empty(); });
    }
    if (png.empty()) {
      response.status = 503;
      response.set_content("no frame yet", "text/plain");
      return;
    }
    response.set_header("X-Ferry-Frame", std::to_string(frameId));
    response.set_header("Cache-Control", "no-store");
    response.set_content(png, "image/png");
  });
  server.Get("/stats", [this](const httplib::Request&, httplib::Response& response) {
    std::lock_guard lock(mutex);
    nlohmann::json j = stats.is_null() ? nlohmann::json::object() : stats;
    if (!j.contains("frames")) j["frames"] = 0;
    j["frame_id"] = frameId;
    j["ranks"] = ranks;
    j["requested"] = {{"camera", cameraJson(requestedCamera)},
                      {"settings", settingsJson(requestedSettings)}};
    nlohmann::json names = nlohmann::json::array();
    for (const CameraView& v : views) names.push_back(v.name);
    j["views"] = names;
    if (limits.volumeLook) j["color_maps"] = colorMapNames();
    if (!limits.fields.empty()) {
      nlohmann::json fields = nlohmann::json::array();
      for (const VolumeField& f : limits.fields)
        fields.push_back({{"name", f.name},
                          {"at", f.atCells ? "cells" : "points"},
                          {"components", f.components},
                          {"range", {f.lo, f.hi}}});
      j["fields"] = fields;
      j["field"] = limits.field >= 0 ? limits.fields[size_t(limits.field)].name : "";
      // A field asked for and not yet shown (the scene is being read again).
      if (pending.flags & ViewChange::kField)
        j["loading_field"] = limits.fields[size_t(pending.field)].name;
      else if (loadingField >= 0)
        j["loading_field"] = limits.fields[size_t(loadingField)].name;
    }
    if (!limits.aovs.empty()) {
      nlohmann::json shown = nlohmann::json::array({"color"});
      for (Aov a : limits.aovs) shown.push_back(aovSpec(a).name);
      j["displays"] = shown;
    }
    j["limits"] = {{"max_side", limits.maxSide},
                   {"max_spp", limits.maxSamplesPerPixel},
                   {"max_depth", limits.maxDepth}};
    response.set_header("Cache-Control", "no-store");
    response.set_content(j.dump(), "application/json");
  });
  // POST handlers read their bodies themselves (readBody).
  using Reader = httplib::ContentReader;
  server.Post("/camera", [this](const httplib::Request& request, httplib::Response& response,
                                const Reader& reader) {
    std::string body;
    if (!readBody(request, response, reader, body)) return;
    change(body, response,
           [&](const std::string& b, ViewChange& c) { applyCameraRequest(b, requestedCamera, c); });
  });
  server.Post("/focus", [this](const httplib::Request& request, httplib::Response& response,
                               const Reader& reader) {
    std::string body;
    if (!readBody(request, response, reader, body)) return;
    change(body, response, applyFocusRequest);
  });
  server.Post("/settings", [this](const httplib::Request& request, httplib::Response& response,
                                  const Reader& reader) {
    std::string body;
    if (!readBody(request, response, reader, body)) return;
    change(body, response, [&](const std::string& b, ViewChange& c) {
      applySettingsRequest(b, requestedSettings, views, limits, c);
    });
  });
  // No body needed; one sent is ignored.
  server.Post("/quit", [this](const httplib::Request&, httplib::Response& response, const Reader&) {
    {
      std::lock_guard lock(mutex);
      pending.flags |= ViewChange::kQuit;
    }
    response.set_content("quitting\n", "text/plain");
  });
  // Unknown paths and methods (404), malformed requests (400): a line
  // saying what was wrong, never an empty answer.
  server.set_error_handler([](const httplib::Request& request, httplib::Response& response) {
    if (!response.body.empty()) return;
    std::string why;
    if (response.status == 404)
      why =
          "no such endpoint (the viewer serves GET /, /frame.png and /stats, and POST "
          "/camera, /focus, /settings and /quit)";
    else if (response.status == 413)
      why = fmt::format("the body is over the {}-byte limit", kMaxBodyBytes);
    else if (response.status == 400)
      why = "a malformed HTTP request";
    else
      why = fmt::format("error {}", response.status);
    response.set_content(fmt::format("{} {}: {}\n", request.method, request.path, why),
                         "text/plain");
  });
}

ViewerServer::ViewerServer(const std::string& bind, int port, std::vector<CameraView> views,
                           const CameraView& initial, const RenderSettings& settings, int ranks,
                           ViewLimits limits)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.bind = bind;
  s.limits = limits;
  s.views = std::move(views);
  s.ranks = ranks;
  s.requestedCamera = initial;
  s.requestedSettings = settings;
  s.routes();
  if (port < 0 || port > 65535)
    throw InputError(fmt::format("port {}: expected 0 (any free port) to 65535", port));
  s.port =
      port == 0 ? s.server.bind_to_any_port(bind) : (s.server.bind_to_port(bind, port) ? port : -1);
  if (s.port <= 0)
    throw InputError(
        fmt::format("cannot listen on {}:{} (in use, or not an address of this "
                    "machine)",
                    bind, port));
  s.thread = std::thread([&s] { s.server.listen_after_bind(); });
  // httplib's stop() does nothing until its loop has begun: wait for it, so
  // that a server destroyed at once still stops.
  while (!s.server.is_running()) std::this_thread::sleep_for(std::chrono::microseconds(100));
}

ViewerServer::~ViewerServer() {
  {
    std::lock_guard lock(state_->mutex);
    state_->stopping = true;
  }
  state_->newFrame.notify_all();
  state_->server.stop();
  if (state_->thread.joinable()) state_->thread.join();
}

int ViewerServer::port() const {
  return state_->port;
}

std::string ViewerServer::url() const {
  const std::string host = state_->bind == "0.0.0.0" ? "127.0.0.1" : state_->bind;
  return fmt::format("http://{}:{}/", host.find(':') != std::string::npos ? "[" + host + "]" : host,
                     state_->port);
}

void ViewerServer::requestQuit() {
  std::lock_guard lock(state_->mutex);
  state_->pending.flags |= ViewChange::kQuit;
}

void ViewerServer::setFields(std::vector<VolumeField> fields, int32_t field) {
  std::lock_guard lock(state_->mutex);
  state_->limits.fields = std::move(fields);
  state_->limits.field = field;
  state_->loadingField = -1;
}

ViewChange ViewerServer::takeChange() {
  std::lock_guard lock(state_->mutex);
  ViewChange change = state_->pending;
  if (gQuitSignal) change.flags |= ViewChange::kQuit;
  if (change.flags & ViewChange::kField) state_->loadingField = change.field;
  if (change.flags & ViewChange::kFocus) state_->focusTaken = true;
  state_->pending.flags = 0;
  return change;
}

bool ViewerServer::restartPending() {
  std::lock_guard lock(state_->mutex);
  constexpr uint32_t kRestart = ViewChange::kCamera | ViewChange::kSettings | ViewChange::kQuit |
                                ViewChange::kFocus | ViewChange::kField;
  return gQuitSignal || (state_->pending.flags & kRestart) != 0;
}

void ViewerServer::publish(const InteractiveFrame& frame) {
  // Encoded outside the lock: requests are answered meanwhile.
  std::string png = encodePng(frame.image.width, frame.image.height, frame.image.rgba);
  nlohmann::json stats = frame.stats.toJson();
  nlohmann::json j;
  j["frames"] = frame.accumulated;
  j["abandoned_frames"] = state_->abandonedTotal += frame.abandoned;
  j["frame"] = stats;
  j["camera"] = cameraJson(frame.camera);
  j["settings"] = settingsJson(frame.settings);
  const RankMemory& m = frame.memory;
  nlohmann::json perRank = nlohmann::json::array();
  for (size_t r = 0; r < m.resident.size(); ++r)
    perRank.push_back({{"rank", r},
                       {"estimated_bytes", m.estimated[r]},
                       {"embree_bytes", m.embree[r]},
                       {"proxy_bytes", m.proxies[r]},
                       {"resident_bytes", m.resident[r]},
                       {"peak_resident_bytes", m.residentPeak[r]}});
  j["memory_per_rank"] = perRank;
  {
    std::lock_guard lock(state_->mutex);
    state_->png = std::move(png);
    state_->stats = std::move(j);
    if (std::exchange(state_->focusTaken, false) && !(state_->pending.flags & ViewChange::kCamera))
      state_->requestedCamera.focalDistance = frame.camera.focalDistance;
    ++state_->frameId;
  }
  state_->newFrame.notify_all();
}

void quitOnSignals() {
  std::signal(SIGINT, onQuitSignal);
  std::signal(SIGTERM, onQuitSignal);
}

}  // namespace ferry
