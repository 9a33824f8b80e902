// The window path (GLFW + GLX). Needs a display: ctest runs it under `xvfb-run -a`
// (test render.window_under_xvfb); elsewhere it skips.
#include <cstdlib>

#include <gtest/gtest.h>

#include "client/render/gl_context.hpp"
#include "client/view/room_view.hpp"
#include "render_checks.hpp"
#include "test_avatar.hpp"

namespace vistel {
namespace {

TEST(RoomViewWindow, OpensAWindowDrawsAndPresents) {
  if (!displayAvailable()) GTEST_SKIP() << "no DISPLAY (ctest runs this under xvfb-run)";
  ViewOptions options;
  options.width = 320;
  options.height = 240;
  options.vsync = false;
  VISTEL_MAKE_VIEW(view, options);
  EXPECT_NE(view->backendDescription().find("GLFW window"), std::string::npos)
      << view->backendDescription();
  EXPECT_FALSE(view->shouldClose());
  EXPECT_EQ(view->framebufferSize(), glm::ivec2(320, 240));

  const test::TestAvatar avatar = test::makeTestAvatar();
  const MemberView m{
      1, "alice", avatar.model, test::makeTestPosture(*avatar.model), glm::mat4(1.0f), false};
  for (int i = 0; i < 3; ++i) {
    view->pollEvents();
    view->render(std::span(&m, 1));
  }
  EXPECT_EQ(view->framesRendered(), 3);
  EXPECT_EQ(view->lastWarning(), "");
  auto frame = view->readFrame();
  ASSERT_TRUE(frame.ok());
  EXPECT_EQ(frame->width, 320);
  // The avatar's chest is in the picture.
  int x = 0, row = 0;
  ASSERT_TRUE(test::pixelOf(view->lastCameras()[0], 240, glm::vec3(0.0f, 1.3f, 0.0f), x, row));
  EXPECT_TRUE(test::isSkin(frame->pixel(x, row)));
}

TEST(RoomViewWindow, OffscreenIsUsedWhenAskedEvenWithADisplay) {
  if (!displayAvailable()) GTEST_SKIP() << "no DISPLAY (ctest runs this under xvfb-run)";
  ViewOptions options;
  options.width = 64;
  options.height = 48;
  options.offscreen = true;
  VISTEL_MAKE_VIEW(view, options);
  EXPECT_NE(view->backendDescription().find("EGL"), std::string::npos);
}

}  // namespace
}  // namespace vistel
