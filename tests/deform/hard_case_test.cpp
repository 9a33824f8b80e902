// The hard case (DESIGN.md §3): the inside of a sharply bent elbow. Judged by numbers:
// penetration between the two limbs, unsolved vertices, inverted faces, triangle
// self-intersections.
#include <gtest/gtest.h>

#include "common/deform/mesh_quality.hpp"
#include "tests/deform/fixtures.hpp"

namespace vistel {
namespace {

struct Measures {
  float rigid_penetration = 0.0f;
  float penetration = 0.0f;
  int unsolved = 0;
  int inverted = 0;
  int rigid_intersections = 0;
  int intersections = 0;
};

// The synthetic arm bent by `degrees`; the limbs away from the elbow region (rest x < 0.24
// and x > 0.36) are tested against each other.
Measures bendAndMeasure(float degrees, const DeformOptions& options) {
  auto arm = test::armBody();
  test::bendArm(*arm, glm::radians(degrees));
  test::Scene scene;
  scene.bodies = {arm.get()};
  scene.options = options;
  scene.step(0.0);
  const SkinMesh& m = arm->mesh;
  std::vector<std::uint32_t> upper_faces, fore_faces, upper_verts, fore_verts;
  for (std::uint32_t f = 0; f < m.indices.size() / 3; ++f) {
    float x = 0.0f;
    for (int k = 0; k < 3; ++k)
      x += m.positions[m.indices[3 * f + static_cast<std::uint32_t>(k)]].x / 3.0f;
    if (x < 0.24f) upper_faces.push_back(f);
    if (x > 0.36f) fore_faces.push_back(f);
  }
  for (std::uint32_t v = 0; v < m.positions.size(); ++v) {
    if (m.positions[v].x < 0.24f) upper_verts.push_back(v);
    if (m.positions[v].x > 0.36f) fore_verts.push_back(v);
  }
  const auto depth = [&](std::span<const glm::vec3> pos) {
    return std::max(penetrationDepth(pos, m.indices, upper_faces, fore_verts, 0.06f),
                    penetrationDepth(pos, m.indices, fore_faces, upper_verts, 0.06f));
  };
  Measures r;
  r.rigid_penetration = depth(arm->rigid_pos);
  r.penetration = depth(arm->state.positions);
  r.unsolved = arm->state.counters.unsolved_vertices;
  r.inverted = countInvertedFaces(arm->rigid_pos, arm->state.positions, m.indices);
  r.rigid_intersections = countSelfIntersections(arm->rigid_pos, m.indices);
  r.intersections = countSelfIntersections(arm->state.positions, m.indices);
  return r;
}

TEST(HardCase, ElbowBent150DegreesLimbsMeetWithoutPenetration) {
  const Measures m = bendAndMeasure(150.0f, DeformOptions{});
  RecordProperty("inverted_faces", m.inverted);
  RecordProperty("self_intersections_rigid", m.rigid_intersections);
  RecordProperty("self_intersections_deformed", m.intersections);
  std::printf(
      "150 deg: penetration rigid %.4f m, deformed %.4f m; unsolved %d; inverted faces %d; "
      "self-intersections rigid %d, deformed %d (contact-surface triangles count too)\n",
      m.rigid_penetration, m.penetration, m.unsolved, m.inverted, m.rigid_intersections,
      m.intersections);
  EXPECT_GE(m.rigid_penetration, 0.01f);
  EXPECT_LE(m.penetration, 0.001f);
  EXPECT_EQ(m.unsolved, 0);
  EXPECT_LE(m.inverted, 30);
}

TEST(HardCase, OppositeLimbTermAndRelaxationHelp) {
  DeformOptions no_collisions;
  no_collisions.collisions = false;
  DeformOptions no_relax;
  no_relax.relax_passes = 0;
  DeformOptions more_relax;
  more_relax.relax_passes = 10;
  more_relax.relax_min_offset = 0.0f;
  const Measures full = bendAndMeasure(150.0f, DeformOptions{});
  const Measures bare = bendAndMeasure(150.0f, no_collisions);
  const Measures stiff = bendAndMeasure(150.0f, no_relax);
  const Measures relaxed = bendAndMeasure(150.0f, more_relax);
  std::printf(
      "150 deg inverted faces: own fields only %d, + collisions %d, + relaxation %d, "
      "+ 10 relaxation passes %d; unsolved %d / %d / %d / %d\n",
      bare.inverted, stiff.inverted, full.inverted, relaxed.inverted, bare.unsolved, stiff.unsolved,
      full.unsolved, relaxed.unsolved);
  // Collision terms (the opposite limb for joint vertices, the limbs for each other)
  // remove the penetration; relaxation reduces inverted faces.
  EXPECT_GE(bare.penetration, 0.01f);
  EXPECT_LE(full.penetration, 0.001f);
  EXPECT_LE(full.unsolved, bare.unsolved);
  EXPECT_LT(full.inverted, stiff.inverted);
  EXPECT_LE(relaxed.inverted, full.inverted);
}

TEST(HardCase, ModerateBendsStayClean) {
  for (float degrees : {60.0f, 90.0f}) {
    const Measures m = bendAndMeasure(degrees, DeformOptions{});
    EXPECT_EQ(m.unsolved, 0) << degrees;
    EXPECT_EQ(m.inverted, 0) << degrees;
    EXPECT_EQ(m.intersections, 0) << degrees;
  }
}

}  // namespace
}  // namespace vistel
