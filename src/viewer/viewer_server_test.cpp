// The viewer's server stops whenever it is destroyed, even at once after it
// started listening (its thread may not have begun to serve yet).
#include "viewer/viewer_server.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <future>

namespace ferry {
namespace {

TEST(ViewerServer, StopsWhenDestroyedAtOnceAfterStarting) {
  CameraView camera;
  camera.from = Vec3f(0, 0, 5);
  RenderSettings settings;
  settings.width = 16;
  settings.height = 9;
  // A server that never stops would hang the suite: the loop runs apart, and
  // a test that waits too long ends the process with a message.
  auto done = std::async(std::launch::async, [&] {
    for (int i = 0; i < 300; ++i) {
      ViewerServer server("127.0.0.1", 0, {camera}, camera, settings, 1);
      EXPECT_GT(server.port(), 0);
    }
  });
  if (done.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
    std::fprintf(stderr, "ViewerServer: a server destroyed at once never stopped\n");
    std::_Exit(1);
  }
  done.get();
}

}  // namespace
}  // namespace ferry
