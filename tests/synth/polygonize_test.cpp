// Polygonization (offline/synth/polygonize.hpp) and simplification
// (offline/synth/simplify.hpp) on hand-made bodies: closed manifolds, across refinement
// borders, with narrow gaps kept open, and at an exact vertex count after simplifying.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "common/anim/skin_mesh.hpp"
#include "offline/synth/polygonize.hpp"
#include "offline/synth/simplify.hpp"
#include "tests/synth/mesh_checks.hpp"

namespace vistel::synth {
namespace {

Shape sphere(const glm::vec3& c, float r) {
  Shape s;
  s.kind = ShapeKind::kEllipsoid;
  s.origin = c;
  s.size = glm::vec3(r);
  finishShape(s);
  return s;
}

// A plan with one part per shape list; parts[0] is the root, the others attach to it.
BodyPlan planOf(const std::vector<std::vector<Shape>>& parts, float attach_blend) {
  BodyPlan plan;
  plan.bounds = {glm::vec3(1e9f), glm::vec3(-1e9f)};
  for (std::size_t p = 0; p < parts.size(); ++p) {
    Part part;
    part.parent = p == 0 ? -1 : 0;
    part.attach_blend = attach_blend;
    for (const Shape& s : parts[p]) {
      part.shapes.push_back(static_cast<int>(plan.shapes.size()));
      plan.shapes.push_back(s);
      plan.bounds.min = glm::min(plan.bounds.min, s.bound_center - glm::vec3(s.bound_radius));
      plan.bounds.max = glm::max(plan.bounds.max, s.bound_center + glm::vec3(s.bound_radius));
    }
    plan.parts.push_back(part);
  }
  return plan;
}

void expectClosedSphereLike(const TriangleMesh& mesh) {
  const test::Topology topo = test::analyseTopology(mesh.positions, mesh.indices);
  EXPECT_TRUE(topo.edges_paired);
  EXPECT_EQ(topo.nonmanifold_vertices, 0);
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler, 2);
  EXPECT_EQ(topo.unused_vertices, 0);
}

TEST(Polygonize, SphereAcrossARefinementBorderIsClosedAndAccurate) {
  const float r = 0.06f;
  const BodyPlan plan = planOf({{sphere(glm::vec3(0.3f, 1.0f, 0.2f), r)}}, 0.0f);
  const ImplicitBody body(plan);
  PolygonizeSettings settings;
  settings.domain = plan.bounds;
  settings.coarse_cell = 0.016f;
  // Refine one corner of the sphere twice, another once: transitions in every direction.
  settings.fine_regions = {{{glm::vec3(0.3f, 1.0f, 0.2f), glm::vec3(0.4f, 1.1f, 0.3f)}, 2},
                           {{glm::vec3(0.2f, 0.9f, 0.1f), glm::vec3(0.28f, 0.98f, 0.18f)}, 1}};
  const TriangleMesh mesh = polygonize(body, settings);
  expectClosedSphereLike(mesh);
  EXPECT_EQ(test::countSelfIntersections(mesh.positions, mesh.indices), 0);
  const double volume = enclosedVolume(mesh.positions, mesh.indices);
  const double exact = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  EXPECT_NEAR(volume, exact, 0.03 * exact);
  // Vertices lie on the surface up to the linear interpolation error.
  for (const glm::vec3& p : mesh.positions) ASSERT_LT(std::abs(body.value(p)), 0.002f);
}

TEST(Polygonize, KeepsNarrowGapsBetweenFingersOpen) {
  // A "palm" sphere with two parallel "fingers" 4 mm apart, blended only with the palm.
  const auto finger = [](float x) {
    Shape c;
    c.kind = ShapeKind::kRoundCone;
    c.origin = glm::vec3(x, 0.0f, 0.0f);
    c.size = glm::vec3(0.09f, 0.0085f, 0.0070f);
    finishShape(c);
    return c;
  };
  const float spacing = 0.0085f * 2.0f + 0.004f;
  const BodyPlan plan = planOf({{sphere(glm::vec3(0.0f, -0.03f, 0.0f), 0.035f)},
                                {finger(-0.5f * spacing)},
                                {finger(0.5f * spacing)}},
                               0.012f);
  const ImplicitBody body(plan);
  PolygonizeSettings settings;
  settings.domain = plan.bounds;
  settings.coarse_cell = 0.016f;
  settings.fine_regions = {{plan.bounds, 3}};
  const TriangleMesh mesh = polygonize(body, settings);
  expectClosedSphereLike(mesh);
  for (const float y : {0.03f, 0.06f, 0.085f}) {
    EXPECT_LT(test::windingNumber(mesh.positions, mesh.indices, glm::vec3(0.0f, y, 0.0f)), 0.5)
        << y;
    EXPECT_GT(test::windingNumber(mesh.positions, mesh.indices, glm::vec3(0.5f * spacing, y, 0.0f)),
              0.5)
        << y;
  }
}

TEST(Simplify, ReachesTheTargetCountAndStaysAClosedManifold) {
  const float r = 0.1f;
  const BodyPlan plan = planOf({{sphere(glm::vec3(0.0f, 1.0f, 0.0f), r)}}, 0.0f);
  const ImplicitBody body(plan);
  PolygonizeSettings settings;
  settings.domain = plan.bounds;
  settings.coarse_cell = 0.008f;
  TriangleMesh mesh = polygonize(body, settings);
  ASSERT_GT(mesh.positions.size(), 2000u);
  SimplifySettings simplify;
  simplify.target_vertices = 600;
  simplify.edge_length.assign(mesh.positions.size(), 0.02f);
  const SimplifyStats stats = synth::simplify(mesh, simplify);
  EXPECT_EQ(mesh.positions.size(), 600u);
  EXPECT_EQ(simplify.edge_length.size(), 600u);
  EXPECT_GT(stats.collapses, 1000);
  expectClosedSphereLike(mesh);
  EXPECT_EQ(test::countSelfIntersections(mesh.positions, mesh.indices), 0);
  const double exact = 4.0 / 3.0 * std::numbers::pi * r * r * r;
  EXPECT_NEAR(enclosedVolume(mesh.positions, mesh.indices), exact, 0.03 * exact);
}

}  // namespace
}  // namespace vistel::synth
