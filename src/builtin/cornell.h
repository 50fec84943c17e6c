// builtin:cornell, the Cornell box with the measured geometry published by
// the Cornell Program of Computer Graphics (millimetres, y up, 0..556 x
// 0..548.8 x 0..559.2): red and green side walls, white floor, ceiling and
// back wall, a short and a tall block, and a quad area light just below the
// ceiling. Black environment, no sun; the view "default" is the classic
// camera (at z = -800 looking +z, vertical field of view 39.3 degrees). With a
// right-handed camera (right = forward x up) the red wall is on the left.
//
// Scale s (default 1) subdivides every quad into n x n cells, n = round(s)
// (at least 1), for tests that want more triangles in the same box.
#pragma once

#include <cstdint>

#include "builtin/scene_plan.h"

namespace ferry::builtin {

ScenePlan planCornell(double scale, uint32_t seed);

}  // namespace ferry::builtin
