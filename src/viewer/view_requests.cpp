#include "viewer/view_requests.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "media/volume_look.h"

namespace ferry {
namespace {

nlohmann::json parseObject(const std::string& body, const std::set<std::string>& allowed) {
  if (body.find_first_not_of(" \t\r\n") == std::string::npos)
    throw RequestError("the body is empty: expected a JSON object");
  nlohmann::json j = nlohmann::json::parse(body, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw RequestError("the body is not valid JSON");
  if (!j.is_object()) throw RequestError("the body must be a JSON object");
  for (const auto& [key, value] : j.items())
    if (!allowed.count(key)) throw RequestError(fmt::format("unknown field '{}'", key));
  return j;
}

double finiteNumber(const nlohmann::json& j, const std::string& key) {
  const nlohmann::json& v = j.at(key);
  if (!v.is_number()) throw RequestError(fmt::format("'{}' must be a number", key));
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw RequestError(fmt::format("'{}' must be finite", key));
  return d;
}

Vec3f vector3(const nlohmann::json& j, const std::string& key) {
  const nlohmann::json& v = j.at(key);
  if (!v.is_array() || v.size() != 3)
    throw RequestError(fmt::format("'{}' must be an array of 3 numbers", key));
  Vec3f out;
  for (int i = 0; i < 3; ++i) {
    if (!v[size_t(i)].is_number())
      throw RequestError(fmt::format("'{}' must be an array of 3 numbers", key));
    const double d = v[size_t(i)].get<double>();
    // Coordinates beyond 1e30 overflow the camera's arithmetic in float.
    if (!std::isfinite(d) || std::abs(d) > 1e30)
      throw RequestError(fmt::format("'{}' must hold finite numbers", key));
    out[i] = float(d);
  }
  return out;
}

int integerIn(const nlohmann::json& j, const std::string& key, int lo, int hi) {
  const nlohmann::json& v = j.at(key);
  if (!v.is_number_integer()) throw RequestError(fmt::format("'{}' must be a whole number", key));
  const int64_t i = v.get<int64_t>();
  if (i < lo || i > hi)
    throw RequestError(fmt::format("'{}' {} is out of range [{}, {}]", key, i, lo, hi));
  return int(i);
}

}  // namespace

void setCamera(const CameraView& c, ViewChange& change) {
  for (int i = 0; i < 3; ++i) {
    change.from[i] = c.from[i];
    change.at[i] = c.at[i];
    change.up[i] = c.up[i];
  }
  change.fovY = c.fovY;
  change.lensRadius = c.lensRadius;
  change.focalDistance = c.focalDistance;
  change.flags |= ViewChange::kCamera;
}

void applyCameraRequest(const std::string& body, const CameraView& current, ViewChange& change) {
  const nlohmann::json j =
      parseObject(body, {"from", "at", "up", "fov", "lens_radius", "focal_distance"});
  if (!j.contains("from") || !j.contains("at")) throw RequestError("'from' and 'at' are required");
  CameraView c = current;
  c.from = vector3(j, "from");
  c.at = vector3(j, "at");
  if (j.contains("up")) c.up = vector3(j, "up");
  if (j.contains("fov")) {
    const double fov = finiteNumber(j, "fov");
    if (!(fov > 0.01 && fov < 179))
      throw RequestError("'fov' must be between 0.01 and 179 degrees");
    c.fovY = float(fov);
  }
  if (j.contains("lens_radius")) {
    const double radius = finiteNumber(j, "lens_radius");
    if (!(radius >= 0)) throw RequestError("'lens_radius' must be 0 (a pinhole) or more");
    c.lensRadius = float(radius);
  }
  if (j.contains("focal_distance")) {
    const double distance = finiteNumber(j, "focal_distance");
    if (!(distance > 0 && distance < 1e30)) throw RequestError("'focal_distance' must be positive");
    c.focalDistance = float(distance);
  }
  const Vec3f forward = c.at - c.from;
  if (!(length(forward) > 0)) throw RequestError("'from' and 'at' must differ");
  if (!(length(cross(normalize(forward), c.up)) > 1e-4f))
    throw RequestError("'up' must not be parallel to the view direction (or zero)");
  setCamera(c, change);
}

void applyFocusRequest(const std::string& body, ViewChange& change) {
  const nlohmann::json j = parseObject(body, {"x", "y"});
  if (!j.contains("x") || !j.contains("y")) throw RequestError("'x' and 'y' are required");
  const double x = finiteNumber(j, "x"), y = finiteNumber(j, "y");
  if (!(x >= 0 && x <= 1 && y >= 0 && y <= 1))
    throw RequestError("'x' and 'y' must be fractions of the image, in [0, 1]");
  change.focusX = float(x);
  change.focusY = float(y);
  change.flags |= ViewChange::kFocus;
}

void applySettingsRequest(const std::string& body, const RenderSettings& current,
                          const std::vector<CameraView>& views, const ViewLimits& limits,
                          ViewChange& change) {
  const nlohmann::json j =
      parseObject(body, {"width", "height", "spp", "max_depth", "exposure", "view",
                         "volume_opacity", "color_map", "display", "field"});
  int width = current.width, height = current.height;
  int spp = current.samplesPerPixel, depth = current.maxDepth;
  if (j.contains("width")) width = integerIn(j, "width", 1, limits.maxSide);
  if (j.contains("height")) height = integerIn(j, "height", 1, limits.maxSide);
  if (j.contains("spp")) spp = integerIn(j, "spp", 1, limits.maxSamplesPerPixel);
  if (j.contains("max_depth")) depth = integerIn(j, "max_depth", 0, limits.maxDepth);
  if (j.contains("exposure")) {
    const double exposure = finiteNumber(j, "exposure");
    if (std::abs(exposure) > 30) throw RequestError("'exposure' must be between -30 and 30 stops");
    change.exposure = float(exposure);
    change.flags |= ViewChange::kExposure;
  }
  if (j.contains("display")) {
    if (!j.at("display").is_string()) throw RequestError("'display' must be a string");
    const std::string name = j.at("display").get<std::string>();
    Aov aov;
    if (name == "color") {
      change.display = -1;
    } else if (aovNamed(name, aov) &&
               std::find(limits.aovs.begin(), limits.aovs.end(), aov) != limits.aovs.end()) {
      change.display = int32_t(aov);
    } else {
      throw RequestError(fmt::format(
          "'display' {}: the frames hold {}", name,
          limits.aovs.empty() ? std::string("the colour only (the viewer was started without AOVs)")
                              : "color, " + aovListText(limits.aovs)));
    }
    change.flags |= ViewChange::kDisplay;
  }
  if (j.contains("view")) {
    if (!j.at("view").is_string()) throw RequestError("'view' must be a string");
    const std::string name = j.at("view").get<std::string>();
    const CameraView* found = nullptr;
    for (const CameraView& v : views)
      if (v.name == name) found = &v;
    if (!found) throw RequestError(fmt::format("no view named '{}'", name));
    setCamera(*found, change);
  }
  if (j.contains("volume_opacity") || j.contains("color_map")) {
    if (!limits.volumeLook)
      throw RequestError("the scene has no volume drawn through a transfer function");
    float opacity =
        (change.flags & ViewChange::kVolume) ? change.volumeOpacity : current.volumeLook.opacity;
    int32_t map = -1;
    if (change.flags & ViewChange::kVolume) {
      map = change.colorMap;
    } else {
      const auto& names = colorMapNames();
      const auto it = std::find(names.begin(), names.end(), current.volumeLook.colorMap);
      if (it != names.end()) map = int32_t(it - names.begin());
    }
    if (j.contains("volume_opacity")) {
      const double o = finiteNumber(j, "volume_opacity");
      if (!(o >= 1.0 / 1024 && o <= 1024))
        throw RequestError("'volume_opacity' must be between 1/1024 and 1024");
      opacity = float(o);
    }
    if (j.contains("color_map")) {
      if (!j.at("color_map").is_string()) throw RequestError("'color_map' must be a string");
      const std::string name = j.at("color_map").get<std::string>();
      const auto& names = colorMapNames();
      const auto it = std::find(names.begin(), names.end(), name);
      if (!name.empty() && it == names.end())
        throw RequestError(
            fmt::format("no colour map named '{}' (known: {})", name, fmt::join(names, ", ")));
      map = name.empty() ? -1 : int32_t(it - names.begin());
    }
    change.volumeOpacity = opacity;
    change.colorMap = map;
    change.flags |= ViewChange::kVolume;
  }
  if (j.contains("field")) {
    if (!j.at("field").is_string()) throw RequestError("'field' must be a string");
    const std::string name = j.at("field").get<std::string>();
    std::vector<std::string> names;
    int32_t found = -1;
    for (size_t i = 0; i < limits.fields.size(); ++i) {
      names.push_back(limits.fields[i].name);
      if (limits.fields[i].name == name) found = int32_t(i);
    }
    if (names.empty())
      throw RequestError("the scene was not read from VTK data with arrays to choose from");
    if (found < 0)
      throw RequestError(
          fmt::format("no array named '{}' (the data holds {})", name, fmt::join(names, ", ")));
    if (found != limits.field) {
      change.field = found;
      change.flags |= ViewChange::kField;
    } else {
      change.flags &= ~uint32_t(ViewChange::kField);  // back to the one shown
    }
  }
  if (width != current.width || height != current.height || spp != current.samplesPerPixel ||
      depth != current.maxDepth) {
    change.width = width;
    change.height = height;
    change.samplesPerPixel = spp;
    change.maxDepth = depth;
    change.flags |= ViewChange::kSettings;
  }
}

}  // namespace ferry
