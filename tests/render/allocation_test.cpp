// No heap allocation per frame after warm-up (STYLE.md): counts operator new calls made
// by any thread during render() once every member's buffers exist.
#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/view/room_view.hpp"
#include "render_checks.hpp"
#include "test_avatar.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel {
namespace {

class CountingDeformer final : public PostSkinDeformer {
 public:
  void deform(const SkinFrame& frame) override { frame.positions[0] += glm::vec3(0.0f); }
};

TEST(RoomViewAllocation, NoHeapAllocationPerFrameAfterWarmUp) {
  ViewOptions options;
  options.width = 160;
  options.height = 120;
  options.offscreen = true;
  options.worker_threads = 3;
  VISTEL_MAKE_VIEW(view, options);
  const test::TestAvatar avatar = test::makeTestAvatar(12);
  std::vector<MemberView> members;
  for (std::uint32_t i = 0; i < 4; ++i) {
    members.push_back(MemberView{i, "member " + std::to_string(i), avatar.model,
                                 test::makeTestPosture(*avatar.model),
                                 glm::translate(glm::mat4(1.0f), glm::vec3(i, 0, 0)), i == 0});
  }
  view->setDeformer(2, std::make_shared<CountingDeformer>());
  for (const StereoMode stereo :
       {StereoMode::kOff, StereoMode::kSideBySide, StereoMode::kAnaglyph}) {
    view->setStereo(stereo);
    for (int i = 0; i < 3; ++i) view->render(members);  // warm-up (driver state, buffers)
    const test::AllocationCounter counter;
    for (int i = 0; i < 5; ++i) {
      members[1].posture.rotations[2] =
          glm::angleAxis(0.1f * static_cast<float>(i), glm::vec3(1, 0, 0));
      view->render(members);
    }
    EXPECT_EQ(counter.count(), 0) << "stereo mode " << static_cast<int>(stereo);
  }
}

}  // namespace
}  // namespace vistel
