// The viewer's API requests, checked: POST /camera, /focus and /settings bodies
// parsed into a ViewChange (session/render_session.h). Pure functions, so
// the malformed-input corpus is a unit test; the server answers 400 with
// the message of a RequestError, and no rank ever sees a bad value.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "render/aov.h"
#include "scene/scene.h"
#include "session/render_session.h"

namespace ferry {

// A request the viewer refuses; what() says why, for the 400 response.
class RequestError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Limits of what a client may ask for (a browser must not be able to make a
// rank allocate gigabytes).
struct ViewLimits {
  int maxSide = 4096;
  int maxSamplesPerPixel = 64;
  int maxDepth = 64;
  // The scene has volumes drawn through a transfer function: "volume_opacity"
  // and "color_map" may restyle them.
  bool volumeLook = false;
  // The AOVs the frames hold (--aov): "display" may show one of them.
  std::vector<Aov> aovs;
  // The arrays of the VTK data the scene was read from, and the one shown:
  // "field" may choose another (the scene is read again).
  std::vector<VolumeField> fields;
  int32_t field = -1;
};

// {"from":[x,y,z],"at":[x,y,z],"up":[x,y,z],"fov":degrees}: from and at are
// required; up and fov keep `current`'s when absent. Adds kCamera to `change`.
void applyCameraRequest(const std::string& body, const CameraView& current, ViewChange& change);

// {"x":fraction,"y":fraction}: focus on the nearest surface under that point
// of the image (y down), both required, in [0, 1]. Adds kFocus to `change`.
void applyFocusRequest(const std::string& body, ViewChange& change);

// {"width":W,"height":H,"spp":N,"max_depth":D,"exposure":stops,"view":"name",
// "volume_opacity":scale,"color_map":"name","display":"name","field":"name"}:
// every field optional; a field absent keeps `current`'s. "view" moves the
// camera to that named view of the scene (`views`); "color_map" is a
// colorMapNames() entry or "" (each volume's own); "display" is "color" or
// one of `limits.aovs` by name; "field" one of `limits.fields` by name.
// Adds kSettings, kExposure, kCamera, kVolume, kDisplay or kField to `change`.
void applySettingsRequest(const std::string& body, const RenderSettings& current,
                          const std::vector<CameraView>& views, const ViewLimits& limits,
                          ViewChange& change);

// `camera` into a ViewChange's camera fields (with kCamera).
void setCamera(const CameraView& camera, ViewChange& change);

}  // namespace ferry
