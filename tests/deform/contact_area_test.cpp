// Contact area and force stay bounded at any depth (issue 25): a rigid ball pressed into the
// face of a real avatar. The skin in contact is the skin that was there before the
// deformation (skin does not stretch a thousandfold): the area a body reports is at most 1.5
// times the ball's cap at that depth (2 pi R d), however far the projection along diverging
// vertex normals stretches nose and lip triangles.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "tests/deform/fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// The ball's centre `depth` metres behind the face's most forward point (+Z), radius r.
glm::vec3 intoTheFace(const test::Body& body, float r, float depth) {
  int head = -1;
  const auto& items = body.model.primitives.items;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (items[i].name == "head") head = static_cast<int>(i);
  }
  EXPECT_GE(head, 0);
  glm::vec3 front(0.0f, 0.0f, -INFINITY);
  for (std::size_t v = 0; v < body.mesh.positions.size(); ++v) {
    if (body.model.calibration.prims[v][0] == head && body.mesh.positions[v].z > front.z)
      front = body.mesh.positions[v];
  }
  return front + glm::vec3(0.0f, 0.0f, r - depth);
}

void pressIntoTheFace(const char* which) {
  const test::RealAvatar* a = test::realAvatar(which);
  ASSERT_NE(a, nullptr);
  BallSpec spec;
  spec.radius = 0.11f;
  for (const float depth : {0.01f, 0.03f, 0.065f}) {
    auto body = test::realBody(*a);
    auto ball = test::ballBody(spec, intoTheFace(*body, spec.radius, depth));
    ball->deform = false;  // rigid
    test::Scene scene;
    scene.bodies = {body.get(), ball.get()};
    scene.step(0.0);
    const double cap = 2.0 * M_PI * spec.radius * depth;
    double area = 0.0, force = 0.0;
    for (const BodyContact& c : body->state.contacts) {
      if (c.partner != 1) continue;
      area = c.area;
      force = glm::length(c.force);
    }
    std::printf(
        "%s: ball %.3f m deep in the face: contact area %.5f m^2 (cap %.5f m^2), force "
        "%.1f N\n",
        which, depth, area, cap, force);
    EXPECT_GT(area, 0.0) << depth;
    EXPECT_LE(area, 1.5 * cap) << which << " at " << depth << " m";
  }
}

TEST(ContactArea, DefaultAvatarFaceAgainstABallStaysBounded) { pressIntoTheFace("default"); }

TEST(ContactArea, MakehumanFaceAgainstABallStaysBounded) {
  VISTEL_REQUIRE_SHARED(glb, "avatars/makehuman_game_engine.glb");
  pressIntoTheFace("makehuman");
}

}  // namespace
}  // namespace vistel
