// RoomDeformer: the client's deformable component runs in the view's skinning workers on
// every drawn body with an implicit model. A soft ball pressed into a rigid one takes its
// imprint (every vertex on or outside the rigid surface) only with the deformer on; the
// contact forces are equal and opposite; a body the view draws differently is left rigid.
#include <algorithm>
#include <limits>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/deform/room_deformer.hpp"
#include "render_checks.hpp"

namespace vistel {
namespace {

std::shared_ptr<const AvatarModel> ball(float radius, float stiffness) {
  BallSpec spec;
  spec.radius = radius;
  spec.stiffness = stiffness;
  Result<std::shared_ptr<const AvatarModel>> made = makeBallAvatar(spec);
  EXPECT_TRUE(made.ok()) << (made.ok() ? "" : made.error().message);
  return made.ok() ? *made : nullptr;
}

Posture at(const glm::vec3& centre) {
  Posture p;
  p.root_translation = centre;
  p.rotations.assign(1, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  return p;
}

// Smallest distance of a member's drawn vertices from a point (model space = room space
// here: placements are the identity).
float closest(const RoomView& view, std::uint32_t id, const glm::vec3& point) {
  float best = std::numeric_limits<float>::max();
  for (const glm::vec3& p : view.skinnedPositions(id))
    best = std::min(best, glm::distance(p, point));
  return best;
}

TEST(RoomDeformer, SoftBallTakesTheRigidBallsImprintOnlyWhenDeformed) {
  ViewOptions options;
  options.width = 160;
  options.height = 120;
  options.offscreen = true;
  options.worker_threads = 2;
  VISTEL_MAKE_VIEW(view, options);
  const float r = 0.1f;
  const glm::vec3 rigid_centre(0.0f, 1.0f, 0.0f);
  const glm::vec3 soft_centre(0.17f, 1.0f, 0.0f);  // 3 cm overlap of the two spheres
  std::vector<MemberView> members;
  members.push_back(
      MemberView{1, "rigid", ball(r, kRigidStiffness), at(rigid_centre), glm::mat4(1.0f), false});
  members.push_back(
      MemberView{2, "soft", ball(r, 2.0e4f), at(soft_centre), glm::mat4(1.0f), false});
  ASSERT_NE(members[0].avatar, nullptr);
  ASSERT_NE(members[1].avatar, nullptr);

  // Without the deformer the soft ball's skin reaches 2.9 cm into the rigid one.
  view->render(members);
  EXPECT_LT(closest(*view, 2, rigid_centre), r - 0.02f);

  RoomDeformer deformer;
  for (int frame = 0; frame < 3; ++frame) {
    ASSERT_TRUE(deformer.sync(members, *view).ok());
    ASSERT_TRUE(deformer.prepare(frame / 60.0).ok());
    view->render(members);
    deformer.finish();
  }
  EXPECT_EQ(deformer.bodyCount(), 2);
  EXPECT_EQ(deformer.rebuilds(), 1);
  EXPECT_EQ(deformer.skippedLastFrame(), 0);
  // The rigid surface is the common contact surface: the soft skin lies on or outside it
  // (within the iso-surface's tolerance), and the rigid ball is not deformed.
  EXPECT_GE(closest(*view, 2, rigid_centre), r - 1.5e-3f);
  EXPECT_GE(closest(*view, 1, rigid_centre), r - 1.5e-3f);
  const std::optional<BodyContactSummary> soft = deformer.contact(2);
  const std::optional<BodyContactSummary> rigid = deformer.contact(1);
  ASSERT_TRUE(soft && rigid);
  EXPECT_GT(soft->area, 0.0);
  EXPECT_GT(soft->force.x, 0.0) << "the soft ball is pushed away from the rigid one (+x)";
  EXPECT_NEAR(glm::length(soft->force + rigid->force), 0.0, 1e-6 * glm::length(soft->force));
  EXPECT_FALSE(deformer.contact(99).has_value());

  // Moving the balls apart: no contact, and no rebuild for a mere change of posture.
  members[1].posture = at(soft_centre + glm::vec3(0.2f, 0.0f, 0.0f));
  ASSERT_TRUE(deformer.sync(members, *view).ok());
  ASSERT_TRUE(deformer.prepare(0.1).ok());
  view->render(members);
  deformer.finish();
  EXPECT_EQ(deformer.rebuilds(), 1);
  EXPECT_EQ(deformer.contact(2)->area, 0.0);

  // A member leaving rebuilds the scene; the remaining body still deforms (alone: not at
  // all, so its drawn vertices are the rigid ones).
  members.pop_back();
  ASSERT_TRUE(deformer.sync(members, *view).ok());
  ASSERT_TRUE(deformer.prepare(0.2).ok());
  view->render(members);
  deformer.finish();
  EXPECT_EQ(deformer.rebuilds(), 2);
  EXPECT_EQ(deformer.bodyCount(), 1);
  EXPECT_EQ(deformer.bodyOf(2), -1);
}

}  // namespace
}  // namespace vistel
