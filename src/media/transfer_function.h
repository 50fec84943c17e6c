// A transfer function as sci-vis tools give a volume one (ParaView, OSPRay,
// barney): a colour map and an opacity ramp over the normalised value
// [0, 1], piecewise linear between control points (held flat beyond the
// first and last). A volume with one renders as a participating medium, as
// barney does: sigma_t = scale x opacity(v), albedo = colour(v).
#pragma once

#include <utility>
#include <vector>

#include "core/math.h"

namespace ferry {

class TransferFunction {
 public:
  struct ColorPoint {
    float x;
    Vec3f rgb;
  };
  struct OpacityPoint {
    float x;
    float opacity;
  };
  // Throws std::invalid_argument (saying what) for no points, positions
  // outside [0, 1] or not increasing, colours outside [0, 1], negative
  // opacities, or a scale that is negative or not finite.
  TransferFunction(std::vector<ColorPoint> colors, std::vector<OpacityPoint> opacities,
                   float scale);
  // ParaView's "Cool to Warm" colour map and a linear opacity ramp from 0,
  // scaled so that the densest values make about 20 mean free paths across
  // a unit box.
  static TransferFunction standard();

  Vec3f color(float v) const;
  float opacity(float v) const;
  float scale() const { return scale_; }
  // Returns a copy with another scale (what a viewer's slider changes).
  TransferFunction withScale(float scale) const;
  // Returns a copy with another colour map (a viewer's choice).
  TransferFunction withColors(std::vector<ColorPoint> colors) const;
  const std::vector<ColorPoint>& colors() const { return colors_; }
  const std::vector<OpacityPoint>& opacities() const { return opacities_; }
  // The smallest and largest opacity over values in [lo, hi].
  std::pair<float, float> opacityRange(float lo, float hi) const;

 private:
  std::vector<ColorPoint> colors_;
  std::vector<OpacityPoint> opacities_;
  float scale_ = 1;
};

}  // namespace ferry
