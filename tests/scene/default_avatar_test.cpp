// DeformScene on the project's default avatar with its implicit model (built here from
// config/avatars/humanoid.toml): a ball pressed into the chest, equal and opposite forces,
// nothing moves at rest, the same bits with 1 and 2 threads.
#include <algorithm>

#include <gtest/gtest.h>

#include "common/base/hash.hpp"
#include "tests/scene/scene_fixtures.hpp"
#include "tests/support/default_avatar.hpp"

namespace vistel {
namespace {

std::shared_ptr<const AvatarModel> defaultAvatar() { return test::defaultAvatarWithModel(); }

// A ball of radius r touching the front of the chest, `depth` metres deep.
glm::vec3 chestBall(const AvatarModel& a, float r, float depth) {
  const int chest = a.skeleton.find("chest");
  const glm::vec3 c(glm::inverse(a.skeleton.inverse_bind[static_cast<std::size_t>(chest)])[3]);
  float front = c.z;
  for (const glm::vec3& p : a.skin.positions) {
    if (std::abs(p.x - c.x) < 0.03f && std::abs(p.y - c.y) < 0.03f) front = std::max(front, p.z);
  }
  return glm::vec3(c.x, c.y, front + r - depth);
}

DeformScene scene(int threads, float depth) {
  const std::shared_ptr<const AvatarModel> avatar = defaultAvatar();
  SceneOptions options;
  options.threads = threads;
  std::vector<SceneBody> bodies = {
      SceneBody{"avatar", avatar, glm::mat4(1.0f), true},
      SceneBody{"ball", test::ballAvatar(0.08f), test::at(chestBall(*avatar, 0.08f, depth)), true}};
  Result<DeformScene> s = DeformScene::create(std::move(bodies), options);
  EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
  return std::move(*s);
}

// Step 1 in two parts (what a room does): the pairs between bodies first, then the own pairs
// of the bodies that deform this frame; the same list as one Step 1 for those bodies, and no
// own pairs for the others.
TEST(DeformSceneDefaultAvatar, OwnPairsOnlyForTheBodiesThatDeform) {
  ASSERT_NE(defaultAvatar(), nullptr);
  DeformScene whole = scene(1, 0.015f);
  DeformScene split = scene(1, 0.015f);
  ASSERT_TRUE(whole.prepare(0.0).ok());
  const auto own = [](const InteractionList& list, int body) {
    return std::count_if(list.pairs.begin(), list.pairs.end(), [body](const Interaction& p) {
      return p.body_a == body && p.body_b == body;
    });
  };
  ASSERT_GT(own(whole.interactions(), 0), 0) << "the avatar's own pairs at rest";
  ASSERT_TRUE(split.prepare(0.0, nullptr, false).ok());
  EXPECT_EQ(own(split.interactions(), 0), 0);
  const std::vector<std::uint8_t> none = {0, 0};
  split.addSelfInteractions(none);
  EXPECT_EQ(own(split.interactions(), 0), 0);
  ASSERT_TRUE(split.prepare(0.0, nullptr, false).ok());
  const std::vector<std::uint8_t> avatar = {1, 0};
  split.addSelfInteractions(avatar);
  EXPECT_EQ(split.interactions().pairs, whole.interactions().pairs);
  EXPECT_EQ(split.interactions().directed, whole.interactions().directed);
  // A second call adds nothing.
  split.addSelfInteractions(avatar);
  EXPECT_EQ(split.interactions().pairs, whole.interactions().pairs);
  // A server's list without the own pairs (its default) gets them the same way; one with
  // them keeps them once.
  InteractionList received;
  for (const Interaction& p : whole.interactions().pairs) {
    if (p.body_a != p.body_b) received.pairs.push_back(p);
  }
  ASSERT_FALSE(received.pairs.empty()) << "the ball touches the chest";
  ASSERT_TRUE(split.prepare(0.0, &received, false).ok());
  split.addSelfInteractions(avatar);
  EXPECT_EQ(split.interactions().pairs, whole.interactions().pairs);
  ASSERT_TRUE(split.prepare(0.0, &whole.interactions(), false).ok());
  split.addSelfInteractions(avatar);
  EXPECT_EQ(split.interactions().pairs, whole.interactions().pairs);
}

TEST(DeformSceneDefaultAvatar, BallInTheChest) {
  ASSERT_NE(defaultAvatar(), nullptr);
  ASSERT_GE(defaultAvatar()->skeleton.find("chest"), 0);
  DeformScene s = scene(1, 0.015f);
  ASSERT_TRUE(s.step(0.0).ok());
  const BodyContactSummary body = s.contactSummary(0);
  const BodyContactSummary ball = s.contactSummary(1);
  EXPECT_GT(body.area, 1e-4);
  EXPECT_EQ(body.partner, 1);
  EXPECT_EQ(ball.partner, 0);
  EXPECT_EQ(body.force + ball.force, glm::dvec3(0.0));
  EXPECT_GT(ball.force.z, 0.0);  // pushed out of the chest, forward
  EXPECT_GT(ball.force.z, 3.0 * std::abs(ball.force.x));
  const DeformState* state = s.deformState(0);
  ASSERT_NE(state, nullptr);
  EXPECT_GT(state->counters.contact_vertices, 10);

  // Far away, at rest: nothing moves.
  s.setPlacement(1, test::at({3.0f, 1.0f, 3.0f}));
  ASSERT_TRUE(s.step(0.1).ok());
  float moved = 0.0f;
  for (std::size_t v = 0; v < s.positions(0).size(); ++v) {
    moved = std::max(moved, glm::length(s.positions(0)[v] - s.rigidPositions(0)[v]));
  }
  EXPECT_LT(moved, 1e-5f);
  EXPECT_EQ(s.contacts().size(), 0u);
}

TEST(DeformSceneDefaultAvatar, SameBitsWithOneAndTwoThreads) {
  ASSERT_NE(defaultAvatar(), nullptr);
  std::uint64_t hashes[2] = {0, 0};
  for (int threads : {1, 2}) {
    DeformScene s = scene(threads, 0.02f);
    std::uint64_t h = kFnvOffset;
    const int shoulder = s.body(0).avatar->skeleton.find("l_upperarm");
    ASSERT_GE(shoulder, 0);
    for (int f = 0; f < 3; ++f) {
      // Raise the left arm a little each frame.
      s.posture(0).rotations[static_cast<std::size_t>(shoulder)] =
          glm::angleAxis(0.2f * static_cast<float>(f), glm::vec3(0.0f, 0.0f, 1.0f));
      ASSERT_TRUE(s.step(f / 30.0).ok());
      h = hashSpan(s.positions(0), h);
      h = hashSpan(s.normals(0), h);
    }
    hashes[threads - 1] = h;
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

}  // namespace
}  // namespace vistel
