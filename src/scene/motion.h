// Motion blur: an instance that moves while the shutter is open, and when a
// ray is. An InstanceMotion is pbrt's animated transform between a start and
// an end transform (pbrt-v3/v4 `ActiveTransform`), held as keys of
// translation, rotation (a quaternion), an upper-triangular scale and skew
// and a shift before the rotation (x -> T + R (U x + shift)), interpolated
// the way Embree interpolates a motion-blurred instance: all linearly but the
// rotation, by slerp. Two keys when the transforms hold no shear (then this
// is pbrt's interpolation exactly), more keys sampled from pbrt's otherwise.
//
// A ray's motion time u in [0, 1] is a pure function of its pixel and sample
// (MotionClock), so any rank that traces or shades it finds the same time.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/math.h"
#include "core/random.h"

namespace ferry {

struct MotionKey {
  Vec3f translation;
  std::array<float, 4> rotation{0, 0, 0, 1};  // quaternion (x, y, z, w)
  // Row-major upper triangle: [sx sxy sxz; 0 sy syz; 0 0 sz].
  float scaleX = 1, skewXY = 0, skewXZ = 0, scaleY = 1, skewYZ = 0, scaleZ = 1;
  Vec3f shift{0, 0, 0};
};

class InstanceMotion {
 public:
  // pbrt's motion from `start` (u = 0) to `end` (u = 1), interpolated in a
  // space whose origin is `pivot` (pbrt-v4 interpolates an instance's
  // transform in its render space, centred on the camera).
  InstanceMotion(const Affine3f& start, const Affine3f& end, Vec3f pivot = Vec3f(0));
  // From stored keys (part files); at least two.
  explicit InstanceMotion(std::vector<MotionKey> keys);
  // A part moving from `innerStart` to `innerEnd` inside an instance moving
  // from `outerStart` to `outerEnd` (pbrt's motion inside ObjectBegin):
  // x -> outer(u) (inner(u) x), each pbrt's interpolation, the outer one
  // about `pivot` (pbrt-v4's render space, as above). Exact (two keys) when
  // the instance is still and a similarity, else sampled.
  static InstanceMotion nested(const Affine3f& outerStart, const Affine3f& outerEnd,
                               const Affine3f& innerStart, const Affine3f& innerEnd,
                               Vec3f pivot = Vec3f(0));

  Affine3f at(float u) const;
  // Every point of `objectBox` moved over u in [0, 1] lies inside (sampled
  // boxes grown by how far a corner can move between samples).
  Box3f sweptBox(const Box3f& objectBox) const;
  const std::vector<MotionKey>& keys() const { return keys_; }

 private:
  std::vector<MotionKey> keys_;
};

// A key's transform, x -> T + R (U x + shift).
Affine3f keyTransform(const MotionKey& key);

// When a camera ray is: pbrt's time, uniform over the shutter [open, close),
// drawn from the pixel's numbers; then u = (time - start) / (end - start)
// clamped to [0, 1], where the scene's motions run from start to end
// (TransformTimes). Every ray of a path shares its camera ray's time.
struct MotionClock {
  float shutterOpen = 0, shutterClose = 1;
  float motionStart = 0, motionEnd = 1;
  uint32_t seed = 0;
  SamplerKind sampler = SamplerKind::Independent;
  // The film's pixel of an image's pixel (random numbers are keyed by it).
  uint32_t imageWidth = 1, filmWidth = 1, x0 = 0, y0 = 0;

  float u(uint32_t pixel, uint32_t sample) const;
};

// What a trace needs to know of its rays' times: none (a scene that does not
// move), or the clock and the sample the rays belong to.
struct PathTimes {
  const MotionClock* clock = nullptr;
  uint32_t sample = 0;
  float of(uint32_t pixel) const { return clock ? clock->u(pixel, sample) : 0.0f; }
};

}  // namespace ferry
