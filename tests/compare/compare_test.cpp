// Surface comparison (offline/compare): topology counts on meshes built to have each fault,
// distances against cases with known answers and against brute force, welding, and
// OpenMesh's reader on a file written here.
#include <cmath>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "offline/compare/mesh_topology.hpp"
#include "offline/compare/surface_distance.hpp"
#include "offline/compare/triangle_soup.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// The box [lo, hi], 8 corners, 12 triangles wound outwards.
TriangleSoup box(glm::vec3 lo, glm::vec3 hi) {
  TriangleSoup s;
  for (int i = 0; i < 8; ++i) {
    s.positions.emplace_back((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
  }
  s.indices = {0, 2, 1, 1, 2, 3,   // z = lo
               4, 5, 6, 5, 7, 6,   // z = hi
               0, 1, 4, 1, 5, 4,   // y = lo
               2, 6, 3, 3, 6, 7,   // y = hi
               0, 4, 2, 2, 4, 6,   // x = lo
               1, 3, 5, 3, 7, 5};  // x = hi
  return s;
}

TriangleSoup unitCube() { return box(glm::vec3(0.0f), glm::vec3(1.0f)); }

// A sphere of radius r: an octahedron subdivided `levels` times, pushed onto the sphere.
TriangleSoup sphere(float r, int levels) {
  TriangleSoup s;
  s.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  s.indices = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  for (int l = 0; l < levels; ++l) {
    std::vector<std::uint32_t> next;
    for (std::size_t t = 0; t < s.indices.size(); t += 3) {
      std::uint32_t m[3];
      for (int e = 0; e < 3; ++e) {
        const glm::vec3 p =
            glm::normalize(s.positions[s.indices[t + e]] + s.positions[s.indices[t + (e + 1) % 3]]);
        m[e] = static_cast<std::uint32_t>(s.positions.size());
        s.positions.push_back(p);  // duplicated at shared edges: weldVertices joins them
      }
      const std::uint32_t a = s.indices[t], b = s.indices[t + 1], c = s.indices[t + 2];
      next.insert(next.end(), {a, m[0], m[2], m[0], b, m[1], m[2], m[1], c, m[0], m[1], m[2]});
    }
    s.indices = next;
  }
  for (glm::vec3& p : s.positions) p = r * glm::normalize(p);
  return weldVertices(s, 1e-6f);
}

TEST(MeshTopology, ACubeIsClosedManifoldAndOriented) {
  const MeshTopology t = analyzeTopology(unitCube());
  EXPECT_EQ(t.vertices, 8);
  EXPECT_EQ(t.triangles, 12);
  EXPECT_TRUE(t.closed());
  EXPECT_TRUE(t.manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.degenerate_triangles, 0);
}

TEST(MeshTopology, AMissingTriangleLeavesAHoleOfThreeEdges) {
  TriangleSoup s = unitCube();
  s.indices.resize(s.indices.size() - 3);
  const MeshTopology t = analyzeTopology(s);
  EXPECT_FALSE(t.closed());
  EXPECT_EQ(t.boundary_edges, 3);
  EXPECT_TRUE(t.manifold());
}

TEST(MeshTopology, AFlippedTriangleDisagreesWithItsNeighbours) {
  TriangleSoup s = unitCube();
  std::swap(s.indices[1], s.indices[2]);
  const MeshTopology t = analyzeTopology(s);
  EXPECT_TRUE(t.closed());
  EXPECT_FALSE(t.oriented());
  EXPECT_EQ(t.misoriented_edges, 3);
}

TEST(MeshTopology, AFinOnAnEdgeMakesItNonManifold) {
  TriangleSoup s = unitCube();
  s.positions.emplace_back(0.5f, -1.0f, -1.0f);
  s.indices.insert(s.indices.end(), {0, 1, 8});  // a third triangle on edge 0-1
  const MeshTopology t = analyzeTopology(s);
  EXPECT_EQ(t.nonmanifold_edges, 1);
  EXPECT_FALSE(t.manifold());
  EXPECT_FALSE(t.closed());
}

TEST(MeshTopology, TwoBoxesTouchingAtACornerMakeANonManifoldVertex) {
  TriangleSoup a = unitCube();
  const TriangleSoup b = box(glm::vec3(1.0f), glm::vec3(2.0f));
  const auto offset = static_cast<std::uint32_t>(a.positions.size());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (std::uint32_t i : b.indices) a.indices.push_back(i + offset);
  const TriangleSoup welded = weldVertices(a, 1e-6f);  // the shared corner (1, 1, 1)
  EXPECT_EQ(welded.positions.size(), 15u);
  const MeshTopology t = analyzeTopology(welded);
  EXPECT_TRUE(t.closed());
  EXPECT_EQ(t.nonmanifold_vertices, 1);
  EXPECT_FALSE(t.manifold());
  EXPECT_EQ(t.components, 1);
  // Apart, they are two closed manifold pieces.
  const MeshTopology apart = analyzeTopology(a);
  EXPECT_TRUE(apart.manifold());
  EXPECT_EQ(apart.components, 2);
}

TEST(TriangleSoup, WeldingJoinsSeamsAndDropsCollapsedTriangles) {
  TriangleSoup s;  // the cube with every triangle's corners its own
  const TriangleSoup cube = unitCube();
  for (std::uint32_t i : cube.indices) {
    s.indices.push_back(static_cast<std::uint32_t>(s.positions.size()));
    s.positions.push_back(cube.positions[i]);
  }
  EXPECT_FALSE(analyzeTopology(s).closed());
  const TriangleSoup welded = weldVertices(s, 1e-6f);
  EXPECT_EQ(welded.positions.size(), 8u);
  EXPECT_TRUE(analyzeTopology(welded).closed());
  // A tolerance wider than the cube joins everything: every triangle collapses.
  EXPECT_TRUE(weldVertices(s, 2.0f).indices.empty());
}

TEST(SurfaceDistance, ASurfaceIsAtZeroFromItself) {
  const TriangleSoup s = sphere(1.0f, 3);
  const SurfaceDistance d = surfaceDistance(s, s);
  EXPECT_LT(d.hausdorff(), 1e-6);
  EXPECT_LT(d.mean(), 1e-6);
  EXPECT_NEAR(d.a_to_b.area, 4.0 * M_PI, 0.2);
}

TEST(SurfaceDistance, AShiftedCubeIsAsFarAsTheShift) {
  const TriangleSoup a = unitCube();
  const TriangleSoup b = box(glm::vec3(0.01f, 0.0f, 0.0f), glm::vec3(1.01f, 1.0f, 1.0f));
  const SurfaceDistance d = surfaceDistance(a, b);
  EXPECT_NEAR(d.hausdorff(), 0.01, 1e-5);
  // The two x faces lie 1 cm from the other cube; the other four almost all on it.
  EXPECT_GT(d.mean(), 0.01 / 3.0);
  EXPECT_LT(d.mean(), 0.01 / 3.0 + 0.002);
}

TEST(SurfaceDistance, ConcentricSpheresAreTheirRadiiApart) {
  const SurfaceDistance d = surfaceDistance(sphere(1.0f, 4), sphere(1.05f, 4));
  // Chords lie inside the sphere by up to ~1 - cos(half an edge's angle): below 2 mm here.
  EXPECT_NEAR(d.hausdorff(), 0.05, 0.003);
  EXPECT_NEAR(d.mean(), 0.05, 0.003);
}

TEST(SurfaceDistance, MatchesBruteForceFromScatteredPoints) {
  // A "surface" of degenerate triangles is a set of points: its directed distance to the
  // sphere is the largest point-to-surface distance, checked against brute force.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f);
  const TriangleSoup target = sphere(1.0f, 3);
  TriangleSoup points;
  double expected_max = 0.0;
  for (int i = 0; i < 300; ++i) {
    const glm::vec3 p(coord(rng), coord(rng), coord(rng));
    const auto at = static_cast<std::uint32_t>(points.positions.size());
    points.positions.push_back(p);
    points.indices.insert(points.indices.end(), {at, at, at});
    const double brute = distanceToSurface(target, p);
    expected_max = std::max(expected_max, brute);
  }
  const SurfaceDistance d = surfaceDistance(points, target, 1);
  EXPECT_NEAR(d.a_to_b.max, expected_max, 1e-6);
  EXPECT_EQ(d.a_to_b.samples, 300u * 3u);
}

TEST(ReadMeshFile, ReadsAnObjAndTriangulatesItsQuads) {
  const std::string path = test::scratchDir() + "/quad_box.obj";
  {
    std::ofstream obj(path);
    obj << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        << "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
  }
  Result<TriangleSoup> soup = readMeshFile(path);
  ASSERT_TRUE(soup.ok()) << soup.error().message;
  EXPECT_EQ(soup->positions.size(), 8u);
  EXPECT_EQ(soup->indices.size(), 36u);
  const MeshTopology t = analyzeTopology(*soup);
  EXPECT_TRUE(t.closed());
  EXPECT_TRUE(t.manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_NEAR(surfaceDistance(*soup, unitCube()).hausdorff(), 0.0, 1e-6);
}

TEST(ReadMeshFile, NamesTheFileItCannotRead) {
  const std::string missing = test::scratchDir() + "/no_such_mesh.ply";
  Result<TriangleSoup> soup = readMeshFile(missing);
  ASSERT_FALSE(soup.ok());
  EXPECT_NE(soup.error().message.find("no_such_mesh.ply"), std::string::npos);
  const std::string junk = test::scratchDir() + "/junk.obj";
  {
    std::ofstream out(junk);
    out << "this is not a mesh\n";
  }
  Result<TriangleSoup> bad = readMeshFile(junk);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("junk.obj"), std::string::npos);
}

}  // namespace
}  // namespace vistel
