// The loft between two rims (offline/synthesize/seam_loft): two open cylinders on one
// axis, a gap between them, are joined into one oriented 2-manifold tube whose new
// vertices lie on the cylinder; a rim split by a chord still closes.
#include <cmath>

#include <gtest/gtest.h>

#include "offline/compare/mesh_topology.hpp"
#include "offline/synthesize/seam_loft.hpp"

namespace vistel {
namespace {

constexpr float kRadius = 0.05f;
constexpr float kPi = 3.14159265f;

// An open cylinder along +Y from y0 to y1, `around` vertices per ring, `rows` rings,
// outward triangles; the first `around` vertices are the bottom ring.
PartMesh cylinder(float y0, float y1, int around, int rows, float turn) {
  TriangleSoup soup;
  for (int r = 0; r < rows; ++r) {
    const float y = y0 + (y1 - y0) * static_cast<float>(r) / static_cast<float>(rows - 1);
    for (int i = 0; i < around; ++i) {
      const float a = 2.0f * kPi * (static_cast<float>(i) + turn) / static_cast<float>(around);
      soup.positions.emplace_back(kRadius * std::cos(a), y, kRadius * std::sin(a));
    }
  }
  for (int r = 0; r + 1 < rows; ++r) {
    for (int i = 0; i < around; ++i) {
      const auto v = [&](int rr, int ii) {
        return static_cast<std::uint32_t>(rr * around + (ii + around) % around);
      };
      // Outward: the angle grows from +X towards +Z, so up then around is outward.
      soup.indices.insert(soup.indices.end(), {v(r, i), v(r + 1, i), v(r + 1, i + 1)});
      soup.indices.insert(soup.indices.end(), {v(r, i), v(r + 1, i + 1), v(r, i + 1)});
    }
  }
  return makePartMesh(std::move(soup), {});
}

RimCurve curveOf(const PartMesh& part, const BoundaryLoop& loop, std::uint32_t first) {
  RimCurve c;
  for (const std::uint32_t v : loop.vertices) {
    c.index.push_back(first + v);
    c.position.push_back(part.mesh.positions[v]);
    c.normal.push_back(part.normals[v]);
  }
  return c;
}

// The rim nearest height y.
const BoundaryLoop& rimAt(const std::vector<BoundaryLoop>& loops, float y) {
  const BoundaryLoop* best = &loops[0];
  for (const BoundaryLoop& l : loops) {
    if (std::abs(l.centroid.y - y) < std::abs(best->centroid.y - y)) best = &l;
  }
  return *best;
}

TEST(SeamLoft, JoinsTwoCylindersAcrossAGap) {
  const PartMesh lower = cylinder(0.0f, 0.1f, 24, 6, 0.0f);
  const PartMesh upper = cylinder(0.16f, 0.26f, 17, 6, 0.3f);  // other count, turned
  const std::vector<BoundaryLoop> lower_rims = boundaryLoops(lower);
  const std::vector<BoundaryLoop> upper_rims = boundaryLoops(upper);
  ASSERT_EQ(lower_rims.size(), 2u);
  ASSERT_EQ(upper_rims.size(), 2u);
  const auto first_upper = static_cast<std::uint32_t>(lower.mesh.positions.size());
  const RimCurve pc = curveOf(lower, rimAt(lower_rims, 0.1f), 0);
  const RimCurve cc = curveOf(upper, rimAt(upper_rims, 0.16f), first_upper);
  const PartField fl(lower), fu(upper);
  const auto first_new = first_upper + static_cast<std::uint32_t>(upper.mesh.positions.size());
  const SeamLoft loft = loftSeam({&pc, &fl}, {&cc, &fu}, first_new);
  EXPECT_GT(loft.rings, 0);
  EXPECT_NEAR(loft.length, 0.06f, 0.01f);

  // The tube: both parts and the loft.
  TriangleSoup tube = lower.mesh;
  for (const glm::vec3& p : upper.mesh.positions) tube.positions.push_back(p);
  for (const std::uint32_t i : upper.mesh.indices) tube.indices.push_back(first_upper + i);
  for (const glm::vec3& p : loft.positions) tube.positions.push_back(p);
  tube.indices.insert(tube.indices.end(), loft.indices.begin(), loft.indices.end());
  const MeshTopology t = analyzeTopology(tube);
  EXPECT_EQ(t.boundary_edges, 24 + 17);  // the two outer ends only
  EXPECT_TRUE(t.manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.degenerate_triangles, 0);
  // New vertices on the cylinder, between the rims.
  for (const glm::vec3& p : loft.positions) {
    EXPECT_NEAR(std::hypot(p.x, p.z), kRadius, 0.002f);
    EXPECT_GT(p.y, 0.1f);
    EXPECT_LT(p.y, 0.16f);
  }
  // Outward triangles: the normal points away from the axis.
  for (std::size_t k = 0; k < loft.indices.size(); k += 3) {
    const glm::vec3 a = tube.positions[loft.indices[k]];
    const glm::vec3 b = tube.positions[loft.indices[k + 1]];
    const glm::vec3 c = tube.positions[loft.indices[k + 2]];
    const glm::vec3 centre = (a + b + c) / 3.0f;
    EXPECT_GT(glm::dot(glm::cross(b - a, c - a), glm::vec3(centre.x, 0.0f, centre.z)), 0.0f);
  }
}

TEST(SeamLoft, ZipsRimsThatTouch) {
  // No gap wider than the rims' spacing: the rims are zipped directly, no rings.
  const PartMesh lower = cylinder(0.0f, 0.1f, 12, 3, 0.0f);
  const PartMesh upper = cylinder(0.102f, 0.2f, 12, 3, 0.5f);
  const auto lower_rims = boundaryLoops(lower);
  const auto upper_rims = boundaryLoops(upper);
  const auto first_upper = static_cast<std::uint32_t>(lower.mesh.positions.size());
  const RimCurve pc = curveOf(lower, rimAt(lower_rims, 0.1f), 0);
  const RimCurve cc = curveOf(upper, rimAt(upper_rims, 0.102f), first_upper);
  const PartField fl(lower), fu(upper);
  const SeamLoft loft = loftSeam({&pc, &fl}, {&cc, &fu}, 1000);
  EXPECT_EQ(loft.rings, 0);
  EXPECT_EQ(loft.indices.size(), 3u * 24u);  // one triangle per rim edge
}

}  // namespace
}  // namespace vistel
