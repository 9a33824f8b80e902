// vistel-avatar compare: an avatar against itself, two meshes a known distance apart (OBJ
// files written here), a mesh with a hole, and a file it cannot read.
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

// A box from (x0, 0, 0) to (x0 + 1, 1, 1) as OBJ quads in `dir`; without its top when
// `open`.
std::string writeBox(const std::string& dir, const std::string& name, float x0, bool open) {
  const std::string path = dir + "/" + name;
  std::ofstream obj(path);
  for (int i = 0; i < 8; ++i) {
    obj << "v " << ((i & 1) ? x0 + 1.0f : x0) << " " << ((i & 2) ? 1 : 0) << " "
        << ((i & 4) ? 1 : 0) << "\n";
  }
  obj << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 1 5 7 3\nf 2 4 8 6\n";
  if (!open) obj << "f 3 7 8 4\n";
  return path;
}

nlohmann::json runJson(const std::string& args, const std::string& dir) {
  const test::ToolRun run = test::runTool("compare --json " + args, dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return nlohmann::json::parse(run.out, nullptr, false);
}

TEST(CompareCli, TheDefaultAvatarIsOneClosedManifoldAtZeroFromItself) {
  const std::string avatar = test::binaryDir() + "/data/default.vavatar";
  const nlohmann::json out = runJson(avatar + " " + avatar, test::scratchDir());
  ASSERT_FALSE(out.is_discarded());
  EXPECT_TRUE(out["a"]["closed"].get<bool>());
  EXPECT_TRUE(out["a"]["manifold"].get<bool>());
  EXPECT_EQ(out["a"]["self_intersecting_pairs"].get<int>(), 0);
  EXPECT_EQ(out["a"]["components"].get<int>(), 1);
  EXPECT_LT(out["distance"]["hausdorff_m"].get<double>(), 1e-6);
}

TEST(CompareCli, MeshesAreAsFarApartAsTheyAreMovedAndHolesAreCounted) {
  const std::string dir = test::scratchDir();  // one call: it empties the folder
  const std::string a = writeBox(dir, "box_a.obj", 0.0f, false);
  const std::string b = writeBox(dir, "box_b.obj", 0.02f, false);
  const std::string open = writeBox(dir, "box_open.obj", 0.0f, true);
  const nlohmann::json moved = runJson(a + " " + b, dir);
  ASSERT_FALSE(moved.is_discarded());
  EXPECT_NEAR(moved["distance"]["hausdorff_m"].get<double>(), 0.02, 1e-5);
  EXPECT_TRUE(moved["a"]["closed"].get<bool>());
  EXPECT_TRUE(moved["b"]["manifold"].get<bool>());
  const nlohmann::json holed = runJson(a + " " + open, dir);
  ASSERT_FALSE(holed.is_discarded());
  EXPECT_FALSE(holed["b"]["closed"].get<bool>());
  EXPECT_EQ(holed["b"]["boundary_edges"].get<int>(), 4);
  // The missing top's points are half the box away from the open box's walls.
  EXPECT_NEAR(holed["distance"]["a_to_b"]["max_m"].get<double>(), 0.5, 1e-5);
  EXPECT_LT(holed["distance"]["b_to_a"]["max_m"].get<double>(), 1e-6);
}

TEST(CompareCli, AFileItCannotReadIsNamed) {
  const std::string dir = test::scratchDir();
  const std::string box = writeBox(dir, "box_c.obj", 0.0f, false);
  const test::ToolRun run = test::runTool("compare " + box + " " + dir + "/missing_part.ply", dir);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("missing_part.ply"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace vistel
