// Calibration and the rest posture (DESIGN.md §3 "Calibration"): every vertex sits on
// F = T in the prototype posture, so with nothing touching deformation moves nothing.
#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/deform/vertex_field.hpp"
#include "tests/deform/fixtures.hpp"

namespace vistel {
namespace {

using test::Body;
using test::Scene;

TEST(Calibration, EveryVertexOnItsSurfaceAtRest) {
  auto arm = test::armBody();
  const ImplicitModel& m = arm->model;
  PosedPrimitives rest;
  std::vector<glm::mat4> identity(3, glm::mat4(1.0f));
  posePrimitives(m.primitives, identity, rest);
  int joint = 0, limb = 0;
  for (int v = 0; v < m.calibration.vertexCount(); ++v) {
    const VertexClass cls = m.calibration.vertex_class[static_cast<std::size_t>(v)];
    if (cls == VertexClass::kFree) continue;
    (cls == VertexClass::kJoint ? joint : limb)++;
    const float f = m.calibration.w[static_cast<std::size_t>(v)] *
                    vertexDensity(m, rest, v, arm->mesh.positions[static_cast<std::size_t>(v)]);
    ASSERT_NEAR(f, m.primitives.iso, 1e-6f) << "vertex " << v;
  }
  EXPECT_GT(joint, 100);
  EXPECT_GT(limb, 1000);
}

TEST(Rest, NothingTouchingMovesNothing) {
  for (const glm::mat4& placement :
       {glm::mat4(1.0f), glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(0.3f, 1.2f, -0.5f)),
                                     0.8f, glm::normalize(glm::vec3(1.0f, 2.0f, 0.5f)))}) {
    auto arm = test::armBody();
    arm->placement = placement;
    Scene scene;
    scene.bodies = {arm.get()};
    scene.step(0.0);
    EXPECT_LT(test::maxDisplacement(*arm), 1e-5f);
    EXPECT_EQ(arm->state.counters.unsolved_vertices, 0);
    EXPECT_EQ(arm->state.counters.contact_vertices, 0);
    // Rigid whole-body motion at rest costs at most one evaluation per vertex (none for
    // limb vertices skinned by their primitive's bone alone).
    EXPECT_EQ(arm->state.counters.evaluations + arm->state.counters.rigid_vertices,
              arm->model.calibration.vertexCount());
    EXPECT_EQ(arm->state.counters.iterations, 0);
    EXPECT_GT(arm->state.counters.rigid_vertices, 0);
  }
}

TEST(Rest, SoftBallAtRestAwayFromTheArm) {
  auto arm = test::armBody();
  BallSpec spec;
  spec.radius = 0.05f;
  spec.stiffness = 3.0e4f;
  auto ball = test::ballBody(spec, glm::vec3(0.3f, 0.5f, 0.0f));
  Scene scene;
  scene.bodies = {arm.get(), ball.get()};
  scene.step(0.0);
  EXPECT_LT(test::maxDisplacement(*arm), 1e-5f);
  EXPECT_LT(test::maxDisplacement(*ball), 1e-5f);
  for (const Interaction& i : scene.list.pairs)
    EXPECT_EQ(i.body_a, i.body_b) << "arm and ball do not touch";
}

}  // namespace
}  // namespace vistel
