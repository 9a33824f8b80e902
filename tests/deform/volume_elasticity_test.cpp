// Propagation keeps volume (DESIGN.md §3 "propagation zone") and elasticity over time
// ("elastic", "plastic", "viscoelastic").
#include <cmath>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "tests/deform/fixtures.hpp"

namespace vistel {
namespace {

using test::Scene;

glm::vec3 dentBallCentre(float depth) { return glm::vec3(0.45f, 0.04f + 0.05f - depth, 0.0f); }

BallSpec ballOf(float stiffness) {
  BallSpec spec;
  spec.radius = 0.05f;
  spec.stiffness = stiffness;
  return spec;
}

// Volume change of the arm with a ball pressed `depth` into the forearm.
double armVolumeChange(float stiffness, float depth, bool propagation) {
  auto arm = test::armBody();
  auto b = test::ballBody(ballOf(stiffness), dentBallCentre(depth));
  b->deform = false;
  Scene scene;
  scene.bodies = {arm.get(), b.get()};
  scene.options.propagation = propagation;
  scene.step(0.0);
  EXPECT_EQ(arm->state.counters.unsolved_vertices, 0);
  EXPECT_GT(arm->state.counters.contact_vertices, 0);
  return enclosedVolume(arm->state.positions, arm->mesh.indices) -
         enclosedVolume(arm->rigid_pos, arm->mesh.indices);
}

TEST(Volume, BallPressedIntoForearmChangesVolumeLessWithPropagation) {
  for (float stiffness : {kRigidStiffness, 3.0e4f}) {
    for (float depth : {0.01f, 0.02f}) {
      const double without = armVolumeChange(stiffness, depth, false);
      const double with = armVolumeChange(stiffness, depth, true);
      EXPECT_LT(without, 0.0) << "the dent loses volume";
      EXPECT_LT(std::abs(with), 0.5 * std::abs(without))
          << "stiffness " << stiffness << " depth " << depth << ": " << with << " vs " << without;
    }
  }
}

// Deepest dent of the arm (most negative offset along the normals) and its vertex.
float dent(const test::Body& arm) {
  float d = 0.0f;
  for (std::size_t v = 0; v < arm.rigid_pos.size(); ++v) {
    d = std::min(d, glm::dot(arm.state.positions[v] - arm.rigid_pos[v], arm.rigid_nrm[v]));
  }
  return d;
}

struct PressRelease {
  std::unique_ptr<test::Body> arm, ball;
  Scene scene;
  explicit PressRelease(std::string_view material) {
    arm = test::armBody(material);
    ball = test::ballBody(ball_spec(), glm::vec3(0.45f, 0.5f, 0.0f));
    ball->deform = false;
    scene.bodies = {arm.get(), ball.get()};
    scene.options.propagation = false;  // the dent alone
  }
  static BallSpec ball_spec() { return ballOf(kRigidStiffness); }
  void at(float depth, double time) {
    ball->placement[3] =
        glm::vec4(depth > 0.0f ? dentBallCentre(depth) : glm::vec3(0.45f, 0.5f, 0.0f), 1.0f);
    scene.step(time);
  }
};

TEST(Elasticity, ElasticSpringsBackAtOnce) {
  PressRelease s("elasticity = \"elastic\"");
  s.at(0.01f, 0.0);
  EXPECT_NEAR(dent(*s.arm), -0.01f, 2e-4f);
  s.at(0.0f, 0.01);
  EXPECT_LT(test::maxDisplacement(*s.arm), 1e-5f);
}

TEST(Elasticity, PlasticKeepsTheDentAndLaterContactsDeepenIt) {
  PressRelease s("elasticity = \"plastic\"");
  s.at(0.008f, 0.0);
  const float first = dent(*s.arm);
  EXPECT_NEAR(first, -0.008f, 2e-4f);
  s.at(0.0f, 0.1);
  EXPECT_NEAR(dent(*s.arm), first, 1e-6f) << "the dent stays after contact ends";
  s.at(0.0f, 5.0);
  EXPECT_NEAR(dent(*s.arm), first, 1e-6f) << "and stays";
  s.at(0.004f, 5.1);
  EXPECT_NEAR(dent(*s.arm), first, 1e-6f) << "a shallower contact changes nothing";
  s.at(0.014f, 5.2);
  const float deeper = dent(*s.arm);
  EXPECT_NEAR(deeper, -0.014f, 2e-4f);
  s.at(0.0f, 5.3);
  EXPECT_NEAR(dent(*s.arm), deeper, 1e-6f);
}

TEST(Elasticity, ViscoelasticRecoversExponentially) {
  const float tau = 0.4f;
  PressRelease s(fmt::format("elasticity = \"viscoelastic\"\ntime_constant = {}", tau));
  s.at(0.01f, 0.0);
  const float d0 = dent(*s.arm);
  EXPECT_NEAR(d0, -0.01f, 2e-4f);
  // Released at t = 0.1: the dent decays as exp(-(t - 0.1) / tau) from its last value.
  double t = 0.1;
  s.at(0.0f, t);
  EXPECT_NEAR(dent(*s.arm), d0 * std::exp(-0.1f / tau), 2e-4f);
  const float d1 = dent(*s.arm);
  for (int k = 1; k <= 10; ++k) {
    t = 0.1 + 0.1 * k;
    s.at(0.0f, t);
    EXPECT_NEAR(dent(*s.arm), d1 * std::exp(-0.1f * k / tau), 2e-4f) << "t " << t;
  }
  s.at(0.0f, 10.0);
  EXPECT_LT(test::maxDisplacement(*s.arm), 1e-5f) << "fully recovered";
}

}  // namespace
}  // namespace vistel
