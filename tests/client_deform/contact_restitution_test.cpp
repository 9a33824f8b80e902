// Restitution in the client's contact forces (issue 25 item 7; prop.hpp "The contact law"):
// RoomDeformer::setMotion gives a body's velocity and restitution to Step 3, which scales a
// pair's force (and the pressures the part forces read) by e^2 while the bodies separate, as
// the ball dynamics do; approaching, or without motion, the force is the elastic law's.
#include <memory>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "client/deform/room_deformer.hpp"
#include "client/view/room_view.hpp"
#include "common/deform/prop.hpp"
#include "tests/client_deform/ball_views.hpp"

namespace vistel {
namespace {

constexpr std::uint32_t kSoftBall = 3, kRigidBall = 4;
constexpr float kSoftRadius = 0.05f;

// The soft ball's contact force (N) in one frame with the rigid ball 1 cm into it, moving at
// `velocity` (x: away from the soft ball when positive) with restitution `e`; the pressure
// its part forces would read is summed into *pressure.
double forceWith(bool set_motion, float velocity, float e, double* pressure) {
  std::unique_ptr<RoomView> view = test::headlessView();
  if (!view) return -1.0;
  RoomDeformer deformer;
  std::vector<MemberView> views = {
      test::ballView(kSoftBall, test::ballAvatar(kSoftRadius, 3.0e4f), glm::vec3(0.0f)),
      test::ballView(kRigidBall, test::ballAvatar(kSoftRadius, kRigidStiffness),
                     glm::vec3(2.0f * kSoftRadius - 0.01f, 0, 0))};
  EXPECT_TRUE(deformer.sync(views, *view).ok());
  if (set_motion) {
    EXPECT_TRUE(deformer.setMotion(kRigidBall, glm::vec3(velocity, 0.0f, 0.0f), e));
  }
  EXPECT_FALSE(deformer.setMotion(99, glm::vec3(0.0f), e)) << "not a body";
  EXPECT_TRUE(deformer.prepare(0.0).ok());
  view->render(views);
  deformer.finish();
  const std::optional<BodyContactSummary> c = deformer.contact(kSoftBall);
  EXPECT_TRUE(c.has_value());
  const std::optional<PartForceInput> in = deformer.partForceInput(kSoftBall);
  EXPECT_TRUE(in.has_value());
  *pressure = 0.0;
  if (in) {
    for (float p : in->pressure) *pressure += p;
  }
  return c ? glm::length(c->force) : -1.0;
}

TEST(ContactRestitution, SeparatingPairsTakeESquaredOfTheForce) {
  double p_still = 0, p_in = 0, p_out = 0, p_elastic = 0;
  const double still = forceWith(false, 0.0f, 1.0f, &p_still);
  const double approaching = forceWith(true, -0.5f, 0.5f, &p_in);
  const double separating = forceWith(true, 0.5f, 0.5f, &p_out);
  const double elastic = forceWith(true, 0.5f, 1.0f, &p_elastic);
  std::printf(
      "soft ball's contact force: still %.3f N, approaching %.3f N, separating (e = 0.5) %.3f N, "
      "separating elastic %.3f N\n",
      still, approaching, separating, elastic);
  ASSERT_GT(still, 0.05);  // (k x the overlap: about 0.2 N)
  EXPECT_DOUBLE_EQ(approaching, still);
  EXPECT_DOUBLE_EQ(elastic, still);
  EXPECT_NEAR(separating / still, 0.25, 1e-6);
  EXPECT_NEAR(p_out / p_still, 0.25, 1e-5) << "the part forces read the same law";
  EXPECT_DOUBLE_EQ(p_in, p_still);
}

}  // namespace
}  // namespace vistel
