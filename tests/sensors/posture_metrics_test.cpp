// posture_metrics: the lag found by cross-correlation is the delay put in (to a fraction of a
// frame, either sign); the largest jump and the jitter of a motion against itself.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/sensors/posture_metrics.hpp"
#include "tests/sensors/humanoid.hpp"

namespace vistel {
namespace {

// A body whose hips sway and whose arms swing, sampled at time t.
Posture swaying(const Skeleton& skeleton, double t) {
  Posture p = restPosture(skeleton);
  p.root_translation = glm::vec3(0.05f * static_cast<float>(std::sin(2.1 * t)), 1.0f,
                                 0.03f * static_cast<float>(std::sin(1.3 * t + 0.4)));
  for (std::size_t j = 1; j < p.rotations.size(); ++j) {
    const float a = 0.3f * static_cast<float>(std::sin(1.7 * t + 0.37 * static_cast<double>(j)));
    p.rotations[j] =
        glm::normalize(glm::angleAxis(a, glm::vec3(1.0f, 0.0f, 0.0f)) * p.rotations[j]);
  }
  return p;
}

TEST(PostureMetrics, LagJumpAndJitter) {
  const Skeleton skeleton = test::makeHumanoid();
  auto roles = resolveJointRoles(skeleton, nullptr);  // canonical names
  ASSERT_TRUE(roles.ok()) << roles.error().message;
  const double dt = 1.0 / 30.0;
  for (double delay : {0.0, 0.05, -0.02, 0.1}) {
    std::vector<Posture> truth, solved;
    for (int f = 0; f < 300; ++f) {
      truth.push_back(swaying(skeleton, f * dt));
      solved.push_back(swaying(skeleton, f * dt - delay));
    }
    const PostureMetrics m = measurePostures(skeleton, *roles, truth, solved, dt);
    EXPECT_NEAR(m.lag_s, delay, 0.15 * dt) << "delay " << delay;
    // The same motion shifted: the same jitter and nearly the same largest jump.
    EXPECT_NEAR(m.jitterRatio(), 1.0, 0.05);
    EXPECT_NEAR(m.jumpRatio(), 1.0, 0.05);
  }
  // A pop: one frame of the solved motion displaced by 10 cm.
  std::vector<Posture> truth, solved;
  for (int f = 0; f < 100; ++f) truth.push_back(swaying(skeleton, f * dt));
  solved = truth;
  solved[50].root_translation.x += 0.1f;
  const PostureMetrics m = measurePostures(skeleton, *roles, truth, solved, dt);
  EXPECT_NEAR(m.max_jump_solved_m, 0.1, 0.01);
  EXPECT_GT(m.jumpRatio(), 3.0);
  EXPECT_GT(m.jitterRatio(), 2.0);
}

}  // namespace
}  // namespace vistel
