// A rigid ball pressed into a real avatar's face and onto its crown, at several depths
// (issue 25): the contact stays bounded and the body keeps its volume.
//  - Area: the skin in contact is the skin that was there before the deformation (skin does
//    not stretch a thousandfold), so the area a body reports is at most 1.5 times the
//    ball's cap at that depth (2 pi R d), however far the projection along diverging
//    vertex normals stretches nose and lip triangles.
//  - Bulge: the skin beside the dent rises no higher than the dent is deep (plus the 5 mm
//    margin of the move bound, DeformOptions::move_margin, which dominates at 1 cm).
//  - Volume: the body's enclosed volume changes by at most 1%.
// Not yet on MakeHuman's crown: its skin there lies outside the head primitive's field (free
// vertices, which take a rigid ball's contact without a contact face of their own); issue
// 25's "every vertex in the model".
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string_view>

#include <gtest/gtest.h>

#include "common/anim/skin_mesh.hpp"
#include "tests/deform/fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// The ball's centre `depth` metres inside the head's outermost point along `dir` (radius r).
glm::vec3 intoTheHead(const test::Body& body, const glm::vec3& dir, float r, float depth) {
  int head = -1;
  const auto& items = body.model.primitives.items;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (items[i].name == "head") head = static_cast<int>(i);
  }
  EXPECT_GE(head, 0);
  glm::vec3 outer(0.0f);
  float best = -INFINITY;
  for (std::size_t v = 0; v < body.mesh.positions.size(); ++v) {
    const float along = glm::dot(body.mesh.positions[v], dir);
    if (body.model.calibration.prims[v][0] == head && along > best) {
      best = along;
      outer = body.mesh.positions[v];
    }
  }
  return outer + (r - depth) * dir;
}

void pressIntoTheHead(const char* which, bool crown) {
  const test::RealAvatar* a = test::realAvatar(which);
  ASSERT_NE(a, nullptr);
  BallSpec spec;
  spec.radius = 0.11f;
  for (const auto& [where, dir] : {std::pair{"face", glm::vec3(0.0f, 0.0f, 1.0f)},
                                   std::pair{"crown", glm::vec3(0.0f, 1.0f, 0.0f)}}) {
    if (!crown && std::string_view(where) == "crown") continue;
    for (const float depth : {0.01f, 0.03f, 0.065f}) {
      auto body = test::realBody(*a);
      auto ball = test::ballBody(spec, intoTheHead(*body, dir, spec.radius, depth));
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
      // The dent (deepest contact vertex, inwards along its skinned normal) and the bulge
      // (highest other vertex, outwards).
      float dent = 0.0f, bulge = 0.0f;
      for (std::size_t v = 0; v < body->rigid_pos.size(); ++v) {
        const float s = glm::dot(body->state.positions[v] - body->rigid_pos[v], body->rigid_nrm[v]);
        if ((body->state.flags[v] & kVertexContact) != 0) {
          dent = std::max(dent, -s);
        } else {
          bulge = std::max(bulge, s);
        }
      }
      const double v0 = enclosedVolume(body->rigid_pos, body->mesh.indices);
      const double v1 = enclosedVolume(body->state.positions, body->mesh.indices);
      const double change = (v1 - v0) / v0;
      std::printf(
          "%s %s, ball %.3f m deep: contact area %.5f m^2 (cap %.5f m^2), force %.1f N; dent "
          "%.4f m, bulge %.4f m; volume %+.3f%%\n",
          which, where, depth, area, cap, force, dent, bulge, 100.0 * change);
      EXPECT_GT(area, 0.0) << where << " " << depth;
      EXPECT_LE(area, 1.5 * cap) << which << " " << where << " at " << depth << " m";
      EXPECT_LE(bulge, dent + DeformOptions{}.move_margin)
          << which << " " << where << " at " << depth << " m";
      EXPECT_LE(std::abs(change), 0.01) << which << " " << where << " at " << depth << " m";
    }
  }
}

TEST(ContactBounds, DefaultAvatarHeadAgainstABall) { pressIntoTheHead("default", true); }

TEST(ContactBounds, MakehumanHeadAgainstABall) {
  VISTEL_REQUIRE_SHARED(glb, "avatars/makehuman_game_engine.glb");
  pressIntoTheHead("makehuman", false);
}

}  // namespace
}  // namespace vistel
