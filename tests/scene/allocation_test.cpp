// After a warm-up frame, DeformScene's per-frame calls allocate nothing (STYLE.md "Kernels
// over spans"): step() on a pool of two threads, and the split frame.
#include <gtest/gtest.h>

#include "tests/scene/scene_fixtures.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel {
namespace {

using test::at;

DeformScene scene(int threads) {
  SceneOptions options;
  options.threads = threads;
  options.skin_chunk = 256;
  options.deform.chunk_size = 128;
  std::vector<SceneBody> bodies = {
      SceneBody{"tube", test::tubeAvatar(), glm::mat4(1.0f), true},
      SceneBody{"ball", test::ballAvatar(0.05f, 2.0e4f), at({0.45f, 0.08f, 0.0f}), true}};
  Result<DeformScene> s = DeformScene::create(std::move(bodies), options);
  EXPECT_TRUE(s.ok());
  return std::move(*s);
}

TEST(DeformSceneAllocation, StepAllocatesNothingAfterWarmUp) {
  DeformScene s = scene(2);
  // Warm-up: the deepest contact first.
  test::bendTube(s.posture(0), 1.2f);
  s.setPlacement(1, at({0.45f, 0.07f, 0.0f}));
  ASSERT_TRUE(s.step(0.0).ok());
  test::bendTube(s.posture(0), 0.0f);
  ASSERT_TRUE(s.step(0.03).ok());
  const Posture posture = s.posture(0);
  const test::AllocationCounter counter;
  for (int f = 0; f < 10; ++f) {
    s.setPosture(0, posture);
    test::bendTube(s.posture(0), 0.1f * static_cast<float>(f));
    s.setPlacement(1, at({0.45f, 0.085f - 0.0015f * static_cast<float>(f), 0.0f}));
    const Status st = s.step(0.06 + f / 30.0);
    if (!st) ADD_FAILURE() << st.error().message;
  }
  EXPECT_EQ(counter.count(), 0);
  EXPECT_GT(s.contactSummary(0).area, 0.0);
}

TEST(DeformSceneAllocation, SplitFrameAllocatesNothingAfterWarmUp) {
  DeformScene s = scene(1);
  std::vector<std::vector<glm::vec3>> pos(2), nrm(2);
  std::vector<DualQuat> dq(3);
  for (int i = 0; i < 2; ++i) {
    pos[static_cast<std::size_t>(i)].resize(s.body(i).avatar->skin.positions.size());
    nrm[static_cast<std::size_t>(i)].resize(s.body(i).avatar->skin.positions.size());
  }
  InteractionList received;
  const auto frame = [&](double time, float bend, float ball_y, bool use_received) {
    test::bendTube(s.posture(0), bend);
    s.setPlacement(1, at({0.45f, ball_y, 0.0f}));
    const Status st = s.prepare(time, use_received ? &received : nullptr);
    if (!st) ADD_FAILURE() << st.error().message;
    for (int i = 0; i < 2; ++i) {
      const auto k = static_cast<std::size_t>(i);
      dq.resize(s.skinMatrices(i).size());  // within the capacity reserved above
      skinMesh(s.body(i).avatar->skin, SkinningMethod::kDualQuaternion, s.skinMatrices(i), dq,
               pos[k], nrm[k]);
      s.deformBody(i, pos[k], nrm[k]);
    }
    s.collectContacts();
  };
  frame(0.0, 1.2f, 0.07f, false);
  received.pairs = s.interactions().pairs;
  frame(0.03, 0.0f, 0.08f, true);
  frame(0.06, 0.0f, 0.08f, false);
  const test::AllocationCounter counter;
  for (int f = 0; f < 10; ++f) {
    frame(0.1 + f / 30.0, 0.1f * static_cast<float>(f), 0.085f - 0.0015f * static_cast<float>(f),
          f % 2 == 0);
  }
  EXPECT_EQ(counter.count(), 0);
  EXPECT_GT(s.contactSummary(0).area, 0.0);
}

}  // namespace
}  // namespace vistel
