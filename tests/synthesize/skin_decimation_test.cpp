// Decimation where flat (offline/synthesize/skin_decimation): a finely tessellated box
// loses most of its flat faces' vertices and keeps its seams; a sphere stays within the
// error bound, closed and oriented; vertices that may not go stay; survivors keep their
// place; bad indices are refused.
#include <array>
#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "offline/compare/mesh_topology.hpp"
#include "offline/compare/surface_distance.hpp"
#include "offline/synthesize/skin_decimation.hpp"

namespace vistel {
namespace {

// A unit box with each face a grid of n x n squares; every face has its own vertices, so
// the box's edges are seams (vertices repeated), as a skin's texture seams are.
TriangleSoup gridBox(int n) {
  TriangleSoup box;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const auto first = static_cast<std::uint32_t>(box.positions.size());
      for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
          glm::vec3 p(0.0f);
          p[axis] = static_cast<float>(side);
          p[(axis + 1) % 3] = static_cast<float>(i) / static_cast<float>(n);
          p[(axis + 2) % 3] = static_cast<float>(j) / static_cast<float>(n);
          box.positions.push_back(p);
        }
      }
      const auto at = [&](int i, int j) {
        return first + static_cast<std::uint32_t>(i * (n + 1) + j);
      };
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          std::array<std::uint32_t, 6> t = {at(i, j), at(i + 1, j),     at(i + 1, j + 1),
                                            at(i, j), at(i + 1, j + 1), at(i, j + 1)};
          if (side == 0) std::swap(t[1], t[2]), std::swap(t[4], t[5]);  // outward
          box.indices.insert(box.indices.end(), t.begin(), t.end());
        }
      }
    }
  }
  return box;
}

// A sphere of radius r: an icosahedron split `levels` times, vertices on the sphere.
TriangleSoup sphere(float r, int levels) {
  const float g = (1.0f + std::sqrt(5.0f)) / 2.0f;
  TriangleSoup s;
  s.positions = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                 {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  s.indices = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
               4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
               6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middle;
    const auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::pair{std::min(a, b), std::max(a, b)};
      const auto [it, added] = middle.emplace(key, static_cast<std::uint32_t>(s.positions.size()));
      if (added) s.positions.push_back(0.5f * (s.positions[a] + s.positions[b]));
      return it->second;
    };
    std::vector<std::uint32_t> next;
    for (std::size_t t = 0; t < s.indices.size(); t += 3) {
      const std::uint32_t a = s.indices[t], b = s.indices[t + 1], c = s.indices[t + 2];
      const std::uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    s.indices = std::move(next);
  }
  for (glm::vec3& p : s.positions) p = r * glm::normalize(p);
  return s;
}

TriangleSoup applied(const TriangleSoup& in, const DecimatedMesh& d) {
  TriangleSoup out;
  for (const std::uint32_t v : d.kept) out.positions.push_back(in.positions[v]);
  out.indices = d.indices;
  return out;
}

TEST(SkinDecimation, AFlatBoxLosesItsInnerVerticesAndKeepsItsSeams) {
  const TriangleSoup box = gridBox(8);
  Result<DecimatedMesh> d = decimateMesh(box.positions, box.indices, {}, {});
  ASSERT_TRUE(d.ok()) << d.error().message;
  const TriangleSoup out = applied(box, *d);
  EXPECT_LT(out.indices.size(), box.indices.size() / 2);
  EXPECT_GT(d->collapses, 0);
  EXPECT_EQ(d->unmanaged_triangles, 0);
  const MeshTopology t = analyzeTopology(weldVertices(out, 1e-6f));
  EXPECT_TRUE(t.closed());
  EXPECT_TRUE(t.manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_EQ(t.components, 1);
  // Every seam vertex (on an edge of the box) is kept, each copy.
  std::size_t on_edges = 0;
  for (const glm::vec3& p : box.positions) {
    int on = 0;
    for (int a = 0; a < 3; ++a) on += p[a] == 0.0f || p[a] == 1.0f ? 1 : 0;
    on_edges += on >= 2 ? 1 : 0;
  }
  EXPECT_GE(out.positions.size(), on_edges);
  // The box is as it was: its surface within the bound both ways.
  const SurfaceDistance sd = surfaceDistance(out, box, 2);
  EXPECT_LT(sd.hausdorff(), 1e-5);
}

TEST(SkinDecimation, ASphereStaysWithinTheBoundClosedAndOriented) {
  const TriangleSoup ball = sphere(0.05f, 3);  // 1,280 triangles, edges about 6 mm
  DecimationOptions options;
  options.max_error_m = 0.001f;
  Result<DecimatedMesh> d = decimateMesh(ball.positions, ball.indices, {}, options);
  ASSERT_TRUE(d.ok()) << d.error().message;
  const TriangleSoup out = applied(ball, *d);
  std::printf("sphere: %zu -> %zu triangles\n", ball.indices.size() / 3, out.indices.size() / 3);
  EXPECT_LT(out.indices.size(), ball.indices.size() * 3 / 4);
  const MeshTopology t = analyzeTopology(out);
  EXPECT_TRUE(t.closed());
  EXPECT_TRUE(t.manifold());
  EXPECT_TRUE(t.oriented());
  const SurfaceDistance sd = surfaceDistance(out, ball, 3);
  EXPECT_LT(sd.a_to_b.max, options.max_error_m + 1e-5);
  EXPECT_LT(sd.b_to_a.max, 2.0 * options.max_error_m);
  // Survivors in input order, triangles' origins in input order.
  for (std::size_t v = 1; v < d->kept.size(); ++v) EXPECT_LT(d->kept[v - 1], d->kept[v]);
  for (std::size_t f = 1; f < d->origin.size(); ++f) EXPECT_LT(d->origin[f - 1], d->origin[f]);
}

TEST(SkinDecimation, VerticesThatMayNotGoStay) {
  const TriangleSoup ball = sphere(0.05f, 3);
  std::vector<std::uint8_t> removable(ball.positions.size(), 0);
  for (std::size_t v = 0; v < removable.size(); ++v)
    removable[v] = ball.positions[v].y > 0.0f ? 1 : 0;
  Result<DecimatedMesh> d = decimateMesh(ball.positions, ball.indices, removable, {});
  ASSERT_TRUE(d.ok()) << d.error().message;
  std::vector<char> kept(ball.positions.size(), 0);
  for (const std::uint32_t v : d->kept) kept[v] = 1;
  int removed = 0;
  for (std::size_t v = 0; v < removable.size(); ++v) {
    if (removable[v] == 0) {
      EXPECT_EQ(kept[v], 1) << v;
    }
    removed += kept[v] == 0 ? 1 : 0;
  }
  EXPECT_GT(removed, 0);
  EXPECT_TRUE(analyzeTopology(applied(ball, *d)).closed());
}

TEST(SkinDecimation, RefusesBadInput) {
  const TriangleSoup ball = sphere(0.05f, 1);
  std::vector<std::uint32_t> bad = ball.indices;
  bad[4] = static_cast<std::uint32_t>(ball.positions.size());
  EXPECT_FALSE(decimateMesh(ball.positions, bad, {}, {}).ok());
  bad.pop_back();
  EXPECT_FALSE(decimateMesh(ball.positions, bad, {}, {}).ok());
  const std::vector<std::uint8_t> few(3, 1);
  EXPECT_FALSE(decimateMesh(ball.positions, ball.indices, few, {}).ok());
  DecimationOptions zero;
  zero.max_error_m = 0.0f;
  EXPECT_FALSE(decimateMesh(ball.positions, ball.indices, {}, zero).ok());
}

}  // namespace
}  // namespace vistel
