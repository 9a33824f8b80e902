// The implicit body (offline/synth/implicit_body.hpp): primitive distances, the smooth
// union, the Lipschitz bound that polygonization relies on, and exact subsets.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "offline/synth/body_plan.hpp"
#include "offline/synth/implicit_body.hpp"

namespace vistel::synth {
namespace {

glm::vec3 randomPoint(std::mt19937& rng, const glm::vec3& lo, const glm::vec3& hi) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  return lo + glm::vec3(u(rng), u(rng), u(rng)) * (hi - lo);
}

TEST(SmoothMin, IsTheMinimumAwayFromTheBlendAndDipsAtMostKOverSix) {
  const float k = 0.04f;
  EXPECT_EQ(smoothMin(0.1f, 0.2f, k), 0.1f);
  EXPECT_EQ(smoothMin(-0.3f, 0.2f, k), -0.3f);
  EXPECT_EQ(smoothMin(0.1f, 0.2f, 0.0f), 0.1f);
  for (float a = -0.05f; a <= 0.05f; a += 0.001f) {
    const float b = 0.01f;
    const float m = smoothMin(a, b, k);
    EXPECT_LE(m, std::min(a, b));
    EXPECT_GE(m, std::min(a, b) - k / 6.0f - 1e-7f);
    EXPECT_FLOAT_EQ(m, smoothMin(b, a, k));
  }
  EXPECT_NEAR(smoothMin(0.0f, 0.0f, k), -k / 6.0f, 1e-7f);
}

TEST(Shapes, DistancesAreExactWhereKnown) {
  // A cone-sphere along +Y from (1,2,3): radius 0.05 at the base, 0.03 at the far end.
  Shape cone;
  cone.kind = ShapeKind::kRoundCone;
  cone.origin = glm::vec3(1.0f, 2.0f, 3.0f);
  cone.size = glm::vec3(0.4f, 0.05f, 0.03f);
  finishShape(cone);
  EXPECT_NEAR(ImplicitBody::shapeValue(cone, cone.origin + glm::vec3(0.0f, -0.15f, 0.0f)), 0.10f,
              1e-6f);
  EXPECT_NEAR(ImplicitBody::shapeValue(cone, cone.origin + glm::vec3(0.0f, 0.53f, 0.0f)), 0.10f,
              1e-6f);
  EXPECT_NEAR(ImplicitBody::shapeValue(cone, cone.origin), -0.05f, 1e-6f);
  // Half-way, the side is at radius ~0.04 (the slant is small).
  EXPECT_NEAR(ImplicitBody::shapeValue(cone, cone.origin + glm::vec3(0.1f, 0.2f, 0.0f)), 0.06f,
              1e-3f);
  // A rounded box: the face centre is on the surface, a point beyond a face at distance d.
  Shape box;
  box.kind = ShapeKind::kRoundBox;
  box.origin = glm::vec3(0.0f, 1.0f, 0.0f);
  box.size = glm::vec3(0.05f, 0.02f, 0.08f);
  box.rounding = 0.01f;
  finishShape(box);
  EXPECT_NEAR(ImplicitBody::shapeValue(box, box.origin + glm::vec3(0.0f, 0.02f, 0.0f)), 0.0f,
              1e-6f);
  EXPECT_NEAR(ImplicitBody::shapeValue(box, box.origin + glm::vec3(0.0f, 0.0f, 0.1f)), 0.02f,
              1e-6f);
  // An ellipsoid: zero on its surface, negative inside.
  Shape e;
  e.kind = ShapeKind::kEllipsoid;
  e.origin = glm::vec3(0.0f);
  e.size = glm::vec3(0.1f, 0.2f, 0.05f);
  finishShape(e);
  EXPECT_NEAR(ImplicitBody::shapeValue(e, glm::vec3(0.0f, 0.2f, 0.0f)), 0.0f, 1e-6f);
  EXPECT_NEAR(ImplicitBody::shapeValue(e, glm::vec3(0.1f, 0.0f, 0.0f)), 0.0f, 1e-6f);
  EXPECT_LT(ImplicitBody::shapeValue(e, glm::vec3(0.0f)), 0.0f);
}

TEST(ImplicitBodyField, IsOneLipschitzAndSubsetsAgreeNearTheSkin) {
  const BodyPlan plan = makeBodyPlan({});
  const ImplicitBody body(plan);
  std::mt19937 rng(7);
  const glm::vec3 lo = plan.bounds.min, hi = plan.bounds.max;
  // 1-Lipschitz for every shape and for the blended field (pairs at short range).
  std::uniform_real_distribution<float> step(-0.02f, 0.02f);
  for (int i = 0; i < 20000; ++i) {
    const glm::vec3 p = randomPoint(rng, lo, hi);
    const glm::vec3 q = p + glm::vec3(step(rng), step(rng), step(rng));
    const float d = glm::distance(p, q);
    ASSERT_LE(std::abs(body.value(p) - body.value(q)), d * 1.0001f + 1e-6f) << i;
    const Shape& s = plan.shapes[static_cast<std::size_t>(i) % plan.shapes.size()];
    ASSERT_LE(std::abs(ImplicitBody::shapeValue(s, p) - ImplicitBody::shapeValue(s, q)),
              d * 1.0001f + 1e-6f)
        << i;
  }
  // In a region, its subset of primitives gives the same field near the skin, and the same
  // sign, never less, elsewhere.
  ShapeSubset subset;
  int near_skin = 0;
  for (int i = 0; i < 50000; ++i) {
    const glm::vec3 center = randomPoint(rng, lo, hi);
    body.select(center, 0.05f, subset);
    const glm::vec3 p = center + glm::vec3(step(rng), step(rng), step(rng));
    const float full = body.value(p);
    const float part = body.value(p, subset);
    ASSERT_EQ(full < 0.0f, part < 0.0f) << i;
    ASSERT_GE(part, full) << i;
    if (std::abs(full) < 0.01f) {
      ++near_skin;
      ASSERT_EQ(part, full) << i;
    }
  }
  EXPECT_GT(near_skin, 200);
}

TEST(ImplicitBodyField, ProjectionLandsOnTheSkin) {
  const BodyPlan plan = makeBodyPlan({});
  const ImplicitBody body(plan);
  // From inside the upper arm and from just outside the thigh.
  const glm::vec3 shoulder = plan.joint_positions[7];
  const glm::vec3 p = body.project(shoulder + glm::vec3(0.1f, -0.05f, 0.06f));
  EXPECT_LT(std::abs(body.value(p)), 1e-5f);
  const glm::vec3 q = body.project(glm::vec3(0.2f, 0.7f, 0.0f));
  EXPECT_LT(std::abs(body.value(q)), 1e-5f);
  EXPECT_NEAR(glm::length(body.gradient(q)), 1.0f, 0.05f);
}

}  // namespace
}  // namespace vistel::synth
