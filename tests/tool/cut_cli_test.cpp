// vistel-avatar cut: the default avatar cut into its 14 limb parts with 3 cm bands; the
// parts are open, 2-manifold pieces of the original surface, the bands separate
// neighbouring parts, PARTS.toml names them; bad bands are refused.
#include <algorithm>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "common/base/file.hpp"
#include "offline/compare/mesh_topology.hpp"
#include "offline/compare/surface_distance.hpp"
#include "offline/compare/triangle_soup.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

float closest(const TriangleSoup& a, const TriangleSoup& b) {
  float best = std::numeric_limits<float>::max();
  for (const glm::vec3& p : a.positions) {
    for (const glm::vec3& q : b.positions) best = std::min(best, glm::distance(p, q));
  }
  return best;
}

TEST(CutCli, TheDefaultAvatarFallsIntoItsLimbPartsWithBandsBetween) {
  const std::string dir = test::scratchDir();
  const std::string avatar = test::binaryDir() + "/data/default.vavatar";
  const test::ToolRun run =
      test::runTool("cut " + avatar + " --band 0.03 -o " + dir + "/parts", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  auto toml = readFileText(dir + "/parts/PARTS.toml");
  ASSERT_TRUE(toml.ok());
  EXPECT_EQ(count(*toml, "[[part]]"), 14u) << *toml;
  EXPECT_EQ(count(*toml, "[[joint]]"), 13u) << *toml;

  std::size_t triangles = 0;
  for (const char* segment :
       {"torso", "head", "l_upperarm", "l_forearm", "l_hand", "r_upperarm", "r_forearm", "r_hand",
        "l_thigh", "l_shin", "l_foot", "r_thigh", "r_shin", "r_foot"}) {
    auto part = readMeshFile(dir + "/parts/" + segment + ".obj");
    ASSERT_TRUE(part.ok()) << part.error().message;
    const MeshTopology t = analyzeTopology(weldVertices(*part, 1e-6f));
    EXPECT_GT(t.boundary_edges, 0) << segment << ": a cut part is open";
    EXPECT_EQ(t.nonmanifold_edges, 0) << segment;
    triangles += part->indices.size() / 3;
  }
  EXPECT_GT(triangles, 15000u);  // most of the 19,996 triangles stay

  // A part is a piece of the original surface: every point of it lies on the avatar.
  const test::ToolRun on =
      test::runTool("compare --json " + dir + "/parts/l_forearm.obj " + avatar, dir);
  ASSERT_EQ(on.exit_code, 0) << on.err;
  const auto at = on.out.find("\"a_to_b\":{\"max_m\":");
  ASSERT_NE(at, std::string::npos) << on.out;
  EXPECT_LT(std::stod(on.out.substr(at + 19)), 1e-5) << on.out;

  // Across each band, neighbouring parts stay at least half a band apart.
  for (const auto& [a, b] : {std::pair{"l_upperarm", "l_forearm"}, std::pair{"l_forearm", "l_hand"},
                             std::pair{"r_thigh", "r_shin"}, std::pair{"torso", "head"}}) {
    auto pa = readMeshFile(dir + "/parts/" + a + ".obj");
    auto pb = readMeshFile(dir + "/parts/" + b + ".obj");
    ASSERT_TRUE(pa.ok() && pb.ok());
    EXPECT_GE(closest(*pa, *pb), 0.015f) << a << " / " << b;
  }
}

TEST(CutCli, ABadBandIsRefused) {
  const std::string dir = test::scratchDir();
  const std::string avatar = test::binaryDir() + "/data/default.vavatar";
  const test::ToolRun run = test::runTool("cut " + avatar + " --band 2 -o " + dir + "/parts", dir);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.err.find("--band"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace vistel
