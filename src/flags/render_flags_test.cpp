// The rendering flags' own parsers (flags/render_flags.h).
#include "flags/render_flags.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "shapes/volume_brick.h"

namespace ferry {
namespace {

TEST(RenderFlags, VolumeBricksAreAutoZeroOrASize) {
  EXPECT_EQ(parseVolumeBricks("auto"), kAutoBricks);
  EXPECT_EQ(parseVolumeBricks("0"), 0);
  EXPECT_EQ(parseVolumeBricks("64"), 64);
  for (const char* bad : {"", "-1", "64x", "big", " 8", "Auto"}) {
    try {
      parseVolumeBricks(bad);
      ADD_FAILURE() << "'" << bad << "' was taken";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--volume-bricks"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace ferry
