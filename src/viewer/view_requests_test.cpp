// The viewer's request corpus: every malformed camera, focus or settings body gets
// a RequestError with a reason and leaves the change untouched; good ones
// become exactly the change they ask for.
#include "viewer/view_requests.h"

#include "media/volume_look.h"

#include <gtest/gtest.h>

#include <tuple>

#include <string>
#include <vector>

namespace ferry {
namespace {

CameraView current() {
  CameraView c;
  c.name = "default";
  c.from = Vec3f(0, 1, 5);
  c.at = Vec3f(0, 1, 0);
  c.up = Vec3f(0, 1, 0);
  c.fovY = 40;
  return c;
}

RenderSettings settings() {
  RenderSettings s;
  s.width = 64;
  s.height = 48;
  s.samplesPerPixel = 1;
  s.maxDepth = 5;
  return s;
}

std::vector<CameraView> views() {
  CameraView top = current();
  top.name = "top";
  top.from = Vec3f(0, 10, 0.1f);
  return {current(), top};
}

// Every body of `corpus` is refused with a reason holding its string.
void expectSettingsRefused(const std::vector<std::pair<std::string, std::string>>& corpus,
                           const ViewLimits& limits) {
  for (const auto& [body, reason] : corpus) {
    ViewChange change;
    try {
      applySettingsRequest(body, settings(), views(), limits, change);
      ADD_FAILURE() << "accepted: " << body;
    } catch (const RequestError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos)
          << body << " -> " << e.what();
    }
  }
}

TEST(ViewRequests, CameraGoodRequestBecomesTheChange) {
  ViewChange change;
  applyCameraRequest(R"({"from":[1,2,3],"at":[0,0,0],"up":[0,0,1],"fov":30})", current(), change);
  EXPECT_EQ(change.flags, ViewChange::kCamera);
  EXPECT_EQ(change.from[0], 1);
  EXPECT_EQ(change.from[2], 3);
  EXPECT_EQ(change.up[2], 1);
  EXPECT_EQ(change.fovY, 30);
  ViewChange keep;  // up and fov may be left out: the current ones stay
  applyCameraRequest(R"({"from":[0,1,9],"at":[0,1,0]})", current(), keep);
  EXPECT_EQ(keep.up[1], 1);
  EXPECT_EQ(keep.fovY, 40);
  EXPECT_EQ(keep.lensRadius, 0);  // the current lens: a pinhole
  ViewChange lens;                // the thin lens travels with the camera
  applyCameraRequest(R"({"from":[0,1,9],"at":[0,1,0],"lens_radius":0.2,"focal_distance":9})",
                     current(), lens);
  EXPECT_FLOAT_EQ(lens.lensRadius, 0.2f);
  EXPECT_FLOAT_EQ(lens.focalDistance, 9);
}

TEST(ViewRequests, MalformedCamerasAreRefusedWithAReason) {
  const std::vector<std::pair<std::string, std::string>> corpus = {
      {"", "the body is empty"},
      {"{", "not valid JSON"},
      {"[1,2,3]", "JSON object"},
      {"\"from\"", "JSON object"},
      {R"({"from":[0,0,1]})", "required"},
      {R"({"at":[0,0,1]})", "required"},
      {R"({"from":[0,0,1],"at":[0,0,0],"zoom":2})", "unknown field 'zoom'"},
      {R"({"from":[0,0],"at":[0,0,0]})", "3 numbers"},
      {R"({"from":[0,0,1,1],"at":[0,0,0]})", "3 numbers"},
      {R"({"from":"0,0,1","at":[0,0,0]})", "3 numbers"},
      {R"({"from":[0,"a",1],"at":[0,0,0]})", "3 numbers"},
      {R"({"from":[0,NaN,1],"at":[0,0,0]})", "not valid JSON"},
      {R"({"from":[0,Infinity,1],"at":[0,0,0]})", "not valid JSON"},
      {R"({"from":[0,1e999,1],"at":[0,0,0]})", "not valid JSON"},  // out of double's range
      {R"({"from":[0,1e31,1],"at":[0,0,0]})", "finite"},
      {R"({"from":[0,0,0],"at":[0,0,0]})", "must differ"},
      {R"({"from":[0,5,0],"at":[0,0,0]})", "parallel"},
      {R"({"from":[0,0,1],"at":[0,0,0],"up":[0,0,0]})", "parallel"},
      {R"({"from":[0,0,1],"at":[0,0,0],"fov":0})", "fov"},
      {R"({"from":[0,0,1],"at":[0,0,0],"fov":180})", "fov"},
      {R"({"from":[0,0,1],"at":[0,0,0],"fov":"wide"})", "number"},
      {R"({"from":[0,0,1],"at":[0,0,0],"lens_radius":-1})", "lens_radius"},
      {R"({"from":[0,0,1],"at":[0,0,0],"focal_distance":0})", "focal_distance"},
  };
  for (const auto& [body, reason] : corpus) {
    ViewChange change;
    try {
      applyCameraRequest(body, current(), change);
      ADD_FAILURE() << "accepted: " << body;
    } catch (const RequestError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos)
          << body << " -> " << e.what();
    }
    EXPECT_EQ(change.flags, 0u) << body;
  }
}

TEST(ViewRequests, AFocusPickBecomesTheChange) {
  ViewChange change;
  applyFocusRequest(R"({"x":0.25,"y":1})", change);
  EXPECT_EQ(change.flags, ViewChange::kFocus);
  EXPECT_EQ(change.focusX, 0.25f);
  EXPECT_EQ(change.focusY, 1.0f);
}

TEST(ViewRequests, MalformedFocusPicksAreRefusedWithAReason) {
  const std::vector<std::pair<std::string, std::string>> corpus = {
      {"", "empty"},
      {"{", "not valid JSON"},
      {"[0.5, 0.5]", "JSON object"},
      {R"({"x":0.5})", "are required"},
      {R"({"y":0.5})", "are required"},
      {R"({"x":"0.5","y":0.5})", "must be a number"},
      {R"({"x":0.5,"y":-0.01})", "in [0, 1]"},
      {R"({"x":1.5,"y":0.5})", "in [0, 1]"},
      {R"({"x":0.5,"y":1e999})", "not valid JSON"},  // out of double's range
      {R"({"x":0.5,"y":0.5,"z":1})", "unknown field 'z'"},
  };
  for (const auto& [body, reason] : corpus) {
    ViewChange change;
    try {
      applyFocusRequest(body, change);
      ADD_FAILURE() << "accepted: " << body;
    } catch (const RequestError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos)
          << body << " -> " << e.what();
    }
    EXPECT_EQ(change.flags, 0u) << body;
  }
}

TEST(ViewRequests, SettingsChangeOnlyWhatTheyName) {
  ViewChange change;
  applySettingsRequest(R"({"spp":4})", settings(), views(), {}, change);
  EXPECT_EQ(change.flags, ViewChange::kSettings);
  EXPECT_EQ(change.samplesPerPixel, 4);
  EXPECT_EQ(change.width, 64);
  EXPECT_EQ(change.maxDepth, 5);
  ViewChange exposure;  // exposure alone does not restart the accumulation
  applySettingsRequest(R"({"exposure":-1.5})", settings(), views(), {}, exposure);
  EXPECT_EQ(exposure.flags, ViewChange::kExposure);
  EXPECT_EQ(exposure.exposure, -1.5f);
  ViewChange view;
  applySettingsRequest(R"({"view":"top"})", settings(), views(), {}, view);
  EXPECT_EQ(view.flags, ViewChange::kCamera);
  EXPECT_EQ(view.from[1], 10);
  ViewChange same;  // asking for what is already there changes nothing
  applySettingsRequest(R"({"width":64,"height":48})", settings(), views(), {}, same);
  EXPECT_EQ(same.flags, 0u);
}

// "display": the colour or an AOV the frames hold, by name; anything else
// (an AOV not held, an unknown name, a number) is refused, naming what is held.
TEST(ViewRequests, DisplayShowsAnAovTheFramesHold) {
  ViewLimits limits;
  limits.aovs = {Aov::Albedo, Aov::Depth};
  ViewChange depth;
  applySettingsRequest(R"({"display":"depth"})", settings(), views(), limits, depth);
  EXPECT_EQ(depth.flags, ViewChange::kDisplay);
  EXPECT_EQ(depth.display, int32_t(Aov::Depth));
  ViewChange color;
  applySettingsRequest(R"({"display":"color"})", settings(), views(), limits, color);
  EXPECT_EQ(color.flags, ViewChange::kDisplay);
  EXPECT_EQ(color.display, -1);
  RenderSettings applied = settings();
  CameraView camera;
  depth.applyTo(camera, applied);
  EXPECT_EQ(applied.toneMapping.aov, int32_t(Aov::Depth));
  for (const auto& [body, reason, held] : std::vector<std::tuple<std::string, std::string, bool>>{
           {R"({"display":"normal"})", "the frames hold color, albedo,depth", true},
           {R"({"display":"glow"})", "the frames hold color, albedo,depth", true},
           {R"({"display":3})", "'display' must be a string", true},
           {R"({"display":"albedo"})", "the colour only", false}}) {
    ViewChange change;
    try {
      applySettingsRequest(body, settings(), views(), held ? limits : ViewLimits{}, change);
      ADD_FAILURE() << "accepted: " << body;
    } catch (const RequestError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos)
          << body << " -> " << e.what();
    }
  }
}

TEST(ViewRequests, AVolumesLookBecomesTheChange) {
  ViewLimits limits;
  limits.volumeLook = true;
  ViewChange change;
  applySettingsRequest(R"({"volume_opacity":4,"color_map":"viridis"})", settings(), views(), limits,
                       change);
  EXPECT_EQ(change.flags, ViewChange::kVolume);
  EXPECT_EQ(change.volumeOpacity, 4);
  ASSERT_GE(change.colorMap, 0);
  EXPECT_EQ(colorMapNames()[size_t(change.colorMap)], "viridis");
  // One field alone keeps the other's current value; "" is the volume's own map.
  RenderSettings s = settings();
  s.volumeLook = {2, "inferno"};
  ViewChange opacityOnly;
  applySettingsRequest(R"({"volume_opacity":0.5})", s, views(), limits, opacityOnly);
  EXPECT_EQ(colorMapNames()[size_t(opacityOnly.colorMap)], "inferno");
  ViewChange own;
  applySettingsRequest(R"({"color_map":""})", s, views(), limits, own);
  EXPECT_EQ(own.colorMap, -1);
  EXPECT_EQ(own.volumeOpacity, 2);
  RenderSettings applied = settings();
  CameraView camera = current();
  change.applyTo(camera, applied);
  EXPECT_EQ(applied.volumeLook.colorMap, "viridis");
  EXPECT_EQ(applied.volumeLook.opacity, 4);
}

TEST(ViewRequests, MalformedVolumeLooksAreRefusedWithAReason) {
  ViewLimits limits;
  limits.volumeLook = true;
  const std::vector<std::pair<std::string, std::string>> corpus = {
      {R"({"volume_opacity":0})", "between 1/1024 and 1024"},
      {R"({"volume_opacity":-2})", "between 1/1024 and 1024"},
      {R"({"volume_opacity":1e6})", "between 1/1024 and 1024"},
      {R"({"volume_opacity":"dense"})", "number"},
      {R"({"color_map":"jet"})", "no colour map named 'jet' (known: cool-to-warm, viridis"},
      {R"({"color_map":7})", "string"},
  };
  expectSettingsRefused(corpus, limits);
  // A scene without such volumes refuses any look.
  ViewChange change;
  EXPECT_THROW(applySettingsRequest(R"({"color_map":"viridis"})", settings(), views(), {}, change),
               RequestError);
}

TEST(ViewRequests, AnotherFieldOfTheDataBecomesTheChange) {
  ViewLimits limits;
  limits.fields = {{"density", false, 1, 0, 1}, {"velocity", false, 3, 0, 11}};
  limits.field = 0;
  ViewChange change;
  applySettingsRequest(R"({"field":"velocity"})", settings(), views(), limits, change);
  EXPECT_EQ(change.flags, ViewChange::kField);
  EXPECT_EQ(change.field, 1);
  // Asking for the one shown again takes a pending change back.
  applySettingsRequest(R"({"field":"density"})", settings(), views(), limits, change);
  EXPECT_EQ(change.flags, 0u);
  const std::vector<std::pair<std::string, std::string>> corpus = {
      {R"({"field":"pressure"})", "no array named 'pressure' (the data holds density, velocity)"},
      {R"({"field":2})", "'field' must be a string"},
  };
  expectSettingsRefused(corpus, limits);
  // A scene not read from VTK data has no field to choose.
  EXPECT_THROW(applySettingsRequest(R"({"field":"density"})", settings(), views(), {}, change),
               RequestError);
}

TEST(ViewRequests, MalformedSettingsAreRefusedWithAReason) {
  const std::vector<std::pair<std::string, std::string>> corpus = {
      {"nonsense", "not valid JSON"},
      {"null", "JSON object"},
      {R"({"width":0})", "out of range"},
      {R"({"width":100000})", "out of range"},
      {R"({"height":-4})", "out of range"},
      {R"({"width":64.5})", "whole number"},
      {R"({"width":"64"})", "whole number"},
      {R"({"spp":0})", "out of range"},
      {R"({"spp":100000})", "out of range"},
      {R"({"max_depth":-1})", "out of range"},
      {R"({"max_depth":1000})", "out of range"},
      {R"({"exposure":1e999})", "not valid JSON"},
      {R"({"exposure":100})", "between"},
      {R"({"exposure":"bright"})", "number"},
      {R"({"view":"nowhere"})", "no view named 'nowhere'"},
      {R"({"view":3})", "string"},
      {R"({"width":64,"frames":3})", "unknown field 'frames'"},
      {R"({"width":99999999999999999999})", "whole number"},
  };
  expectSettingsRefused(corpus, {});
}

}  // namespace
}  // namespace ferry
