// Contact (DESIGN.md §3 "Collision terms"): both bodies settle on one common surface; a
// rigid partner's surface is where the soft body ends; the collision term is continuous
// across both zone borders; forces are equal and opposite and grow with depth.
#include <cmath>

#include <gtest/gtest.h>

#include "common/deform/vertex_field.hpp"
#include "tests/deform/fixtures.hpp"

namespace vistel {
namespace {

using test::Body;
using test::Scene;

constexpr float kArmRadius = 0.04f;
constexpr float kContactBallRadius = 0.05f;

// A ball above the middle of the forearm, pressed `depth` metres into it.
glm::vec3 contactBallCentre(float depth) {
  return glm::vec3(0.45f, kArmRadius + kContactBallRadius - depth, 0.0f);
}

BallSpec ballSpec(float stiffness) {
  BallSpec spec;
  spec.radius = kContactBallRadius;
  spec.stiffness = stiffness;
  return spec;
}

TEST(Contact, SoftBodiesShareOneSurface) {
  auto arm = test::armBody();
  auto ball = test::ballBody(ballSpec(3.0e4f), contactBallCentre(0.012f));
  Scene scene;
  scene.bodies = {arm.get(), ball.get()};
  scene.step(0.0);
  const PosedPrimitive& ball_prim = ball->posed.items[0];
  const PosedPrimitive& fore = arm->posed.items[1];
  ASSERT_EQ(arm->model.primitives.items[1].name, "fore");
  int arm_contacts = 0, ball_contacts = 0;
  for (std::size_t v = 0; v < arm->mesh.positions.size(); ++v) {
    if (arm->state.contact_body[v] != 1) continue;
    ++arm_contacts;
    // One surface: w_v D_v = w_i F_i, the partner's field scaled by its skin weight (taken
    // where the vertex started).
    const glm::vec3 p = arm->state.positions[v];
    const float d =
        arm->model.calibration.w[v] * vertexDensity(arm->model, arm->posed, static_cast<int>(v), p);
    const float f = skinWeight(ball_prim, arm->rigid_pos[v]) * primitiveField(ball_prim, p);
    EXPECT_LT(std::abs(d - f), 1e-4f) << "arm vertex " << v;
  }
  for (std::size_t v = 0; v < ball->mesh.positions.size(); ++v) {
    if (ball->state.contact_body[v] != 0) continue;
    ++ball_contacts;
    const glm::vec3 p = ball->state.positions[v];
    const float d = ball->model.calibration.w[v] *
                    vertexDensity(ball->model, ball->posed, static_cast<int>(v), p);
    const float f = skinWeight(fore, ball->rigid_pos[v]) * primitiveField(fore, p);
    EXPECT_LT(std::abs(d - f), 1e-4f) << "ball vertex " << v;
  }
  EXPECT_GT(arm_contacts, 5);
  EXPECT_GT(ball_contacts, 5);
  EXPECT_EQ(arm->state.counters.unsolved_vertices, 0);
  EXPECT_EQ(ball->state.counters.unsolved_vertices, 0);
  // Both moved: each takes part of the interpenetration.
  EXPECT_GT(test::maxDisplacement(*arm), 0.003f);
  EXPECT_GT(test::maxDisplacement(*ball), 0.003f);
}

TEST(Contact, RigidPartnerLeavesItsExactImprint) {
  auto arm = test::armBody();
  auto ball = test::ballBody(ballSpec(kRigidStiffness), contactBallCentre(0.015f));
  ball->deform = false;
  Scene scene;
  scene.bodies = {arm.get(), ball.get()};
  scene.step(0.0);
  const PosedPrimitive& ball_prim = ball->posed.items[0];
  const glm::vec3 c = contactBallCentre(0.015f);
  int contacts = 0;
  for (std::size_t v = 0; v < arm->mesh.positions.size(); ++v) {
    // Every arm vertex ends on or outside the ball.
    const glm::vec3 p = arm->state.positions[v];
    EXPECT_GT(glm::length(p - c), kContactBallRadius - 1e-5f)
        << "vertex " << v << " inside the ball";
    if (arm->state.contact_body[v] != 1) continue;
    ++contacts;
    EXPECT_LT(std::abs(primitiveField(ball_prim, p) - 0.5f), 1e-4f) << "vertex " << v;
    EXPECT_NEAR(glm::length(p - c), kContactBallRadius, 2e-5f) << "vertex " << v;
  }
  EXPECT_GT(contacts, 10);
}

TEST(Contact, CollisionTermIsContinuousAcrossBothZoneBorders) {
  // The term as a function of x = omega F - iso.
  const float width = 0.45f, bulge = 0.3f;
  EXPECT_EQ(collisionTerm(1e-7f, bulge, width), -1e-7f);
  EXPECT_NEAR(collisionTerm(-1e-7f, bulge, width), 0.0f, 1e-5f);
  EXPECT_NEAR(collisionTerm(-width + 1e-7f, bulge, width), 0.0f, 1e-5f);
  EXPECT_EQ(collisionTerm(-width - 1e-7f, bulge, width), 0.0f);
  EXPECT_NEAR(collisionTerm(-width / 3.0f, bulge, width), bulge, 1e-6f);  // peak at s = 1/3
  // And in space: along an arm vertex's normal line through both borders, the solved
  // function changes by no more than its slope allows between close samples.
  auto arm = test::armBody();
  auto ball = test::ballBody(ballSpec(3.0e4f), contactBallCentre(0.012f));
  Scene scene;
  scene.bodies = {arm.get(), ball.get()};
  scene.step(0.0);
  int v_top = -1;
  float best = -1.0f;
  for (std::size_t v = 0; v < arm->mesh.positions.size(); ++v) {
    const glm::vec3 p = arm->rigid_pos[v];
    if (std::abs(p.x - 0.47f) < 0.006f && p.y > best) {
      best = p.y;
      v_top = static_cast<int>(v);
    }
  }
  ASSERT_GE(v_top, 0);
  const DeformInput in = arm->input(0.0);
  const glm::vec3 p0 = arm->rigid_pos[static_cast<std::size_t>(v_top)];
  const glm::vec3 n = arm->rigid_nrm[static_cast<std::size_t>(v_top)];
  const PosedPrimitive& ball_prim = ball->posed.items[0];
  const float w = arm->model.calibration.w[static_cast<std::size_t>(v_top)];
  int borders = 0;
  float prev_x = w * primitiveField(ball_prim, p0 - 0.03f * n) - 0.5f;
  float prev_g = vertexFunction(arm->model, scene.views, 0, in, arm->state, scene.options, v_top,
                                p0 - 0.03f * n);
  const float step = 1e-6f;
  for (float s = -0.03f + step; s < 0.03f; s += step) {
    const glm::vec3 p = p0 + s * n;
    const float x = w * primitiveField(ball_prim, p) - 0.5f;
    const float g =
        vertexFunction(arm->model, scene.views, 0, in, arm->state, scene.options, v_top, p);
    const float zone = arm->model.primitives.propagation_width;
    const bool crossed = (prev_x > 0.0f) != (x > 0.0f) || (prev_x > -zone) != (x > -zone);
    if (crossed) {
      ++borders;
      EXPECT_LT(std::abs(g - prev_g), 0.02f) << "jump at s=" << s;
    }
    prev_x = x;
    prev_g = g;
  }
  EXPECT_EQ(borders, 2);
}

TEST(Contact, ForcesAreEqualOppositeAndGrowWithDepth) {
  double last = 0.0;
  for (float depth : {0.004f, 0.008f, 0.012f, 0.016f}) {
    auto arm = test::armBody();
    auto ball = test::ballBody(ballSpec(3.0e4f), contactBallCentre(depth));
    Scene scene;
    scene.bodies = {arm.get(), ball.get()};
    scene.step(0.0);
    ASSERT_EQ(scene.contacts.size(), 1u);
    const PairContact& pc = scene.contacts[0];
    const glm::dvec3 on_arm = netContactForce(scene.contacts, 0);
    const glm::dvec3 on_ball = netContactForce(scene.contacts, 1);
    EXPECT_EQ(on_arm + on_ball, glm::dvec3(0.0));
    // The ball above pushes the arm down; each side's own measurement agrees in direction
    // and roughly in size.
    EXPECT_LT(on_arm.y, 0.0);
    ASSERT_EQ(arm->state.contacts.size(), 1u);
    ASSERT_EQ(ball->state.contacts.size(), 1u);
    const glm::dvec3 fa = arm->state.contacts[0].force;
    const glm::dvec3 fb = ball->state.contacts[0].force;
    EXPECT_LT(fa.y, 0.0);
    EXPECT_GT(fb.y, 0.0);
    EXPECT_NEAR(fa.y / -fb.y, 1.0, 0.5);
    EXPECT_GT(pc.area_a, 0.0);
    EXPECT_GT(pc.area_b, 0.0);
    const double magnitude = glm::length(on_arm);
    EXPECT_GT(magnitude, last) << "depth " << depth;
    last = magnitude;
  }
}

}  // namespace
}  // namespace vistel
