// The vistel-avatar program: info, pose and default on real files, and bad command lines
// and files (a message on stderr, a non-zero exit, never a crash).
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "tests/gltf/gltf_test_models.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

std::string chainGlb(const std::string& dir) {
  const std::string path = dir + "/chain.glb";
  const std::vector<std::uint8_t> bytes = test::makeChainGltf().file.glb();
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  return path;
}

TEST(VistelAvatarCli, InfoOnTheSharedAvatar) {
  VISTEL_REQUIRE_SHARED(avatar, test::kMakeHumanGlb);
  const std::string dir = test::scratchDir();
  const test::ToolRun text = test::runTool("info " + avatar, dir);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("vertices:        13380"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("triangles:       26756"), std::string::npos);
  EXPECT_NE(text.out.find("joints:          53"), std::string::npos);
  EXPECT_NE(text.out.find("lowerarm_l <- upperarm_l"), std::string::npos);

  const test::ToolRun json = test::runTool("info --json " + avatar, dir);
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json info = nlohmann::json::parse(json.out);
  EXPECT_EQ(info["vertices"], 13380);
  EXPECT_EQ(info["triangles"], 26756);
  ASSERT_EQ(info["joints"].size(), 53u);
  EXPECT_EQ(info["joints"][0], "Root");
  EXPECT_EQ(info["parents"][1], 0);
  EXPECT_LE(info["max_influences"].get<int>(), 4);
  EXPECT_NEAR(info["bbox_max"][1].get<double>() - info["bbox_min"][1].get<double>(), 1.666, 0.03);
}

TEST(VistelAvatarCli, InfoOnGltfAndVavatarFiles) {
  const std::string dir = test::scratchDir();
  const test::ChainGltf chain = test::makeChainGltf();
  const std::string gltf = chain.file.writeGltfWithBin(dir, "chain");
  test::ToolRun run = test::runTool("info --json " + gltf, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  nlohmann::json info = nlohmann::json::parse(run.out);
  EXPECT_EQ(info["joints"].size(), 10u);
  EXPECT_EQ(info["max_influences"], 8);

  Result<AvatarModel> avatar = importGltfAvatar(gltf);
  ASSERT_TRUE(avatar.ok());
  ASSERT_TRUE(saveAvatar(*avatar, dir + "/chain.vavatar").ok());
  run = test::runTool("info --json " + dir + "/chain.vavatar", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  info = nlohmann::json::parse(run.out);
  EXPECT_EQ(info["vertices"], avatar->skin.vertexCount());
  EXPECT_EQ(info["joints"][3], avatar->skeleton.names[3]);
}

TEST(VistelAvatarCli, PoseRestRoundTripsThroughReimport) {
  VISTEL_REQUIRE_SHARED(avatar_path, test::kMakeHumanGlb);
  const std::string dir = test::scratchDir();
  const test::ToolRun run =
      test::runTool("pose " + avatar_path + " --rest --out " + dir + "/rest.glb", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Result<AvatarModel> original = importGltfAvatar(avatar_path);
  Result<AvatarModel> posed = importGltfAvatar(dir + "/rest.glb");
  ASSERT_TRUE(original.ok() && posed.ok());
  EXPECT_EQ(posed->skeleton.names, original->skeleton.names);
  ASSERT_EQ(posed->skin.positions.size(), original->skin.positions.size());
  for (std::size_t v = 0; v < posed->skin.positions.size(); ++v) {
    ASSERT_LT(glm::distance(posed->skin.positions[v], original->skin.positions[v]), 1e-5f) << v;
  }
  VISTEL_VALIDATE_OR_SKIP(verdict, dir + "/rest.glb");
  EXPECT_EQ(verdict["errors"], 0) << verdict.dump();
}

TEST(VistelAvatarCli, PoseBvhFrameWithLbsAndDqs) {
  VISTEL_REQUIRE_SHARED(avatar_path, test::kMakeHumanGlb);
  VISTEL_REQUIRE_SHARED(clip, "mocap/cmu/01_01.bvh");
  const std::string dir = test::scratchDir();
  Result<AvatarModel> original = importGltfAvatar(avatar_path);
  ASSERT_TRUE(original.ok());
  for (const char* method : {"lbs", "dqs"}) {
    const std::string out = dir + "/" + method + ".glb";
    const test::ToolRun run =
        test::runTool("pose " + avatar_path + " --bvh " + clip + " --frame 150 --skinning " +
                          method + " --out " + out,
                      dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    Result<AvatarModel> posed = importGltfAvatar(out);
    ASSERT_TRUE(posed.ok()) << posed.error().message;
    EXPECT_EQ(posed->skeleton.names, original->skeleton.names);
    EXPECT_EQ(posed->skin.vertexCount(), 13380);
    // The posture moved the vertices.
    double moved = 0.0;
    for (std::size_t v = 0; v < posed->skin.positions.size(); ++v) {
      moved = std::max<double>(
          moved, glm::distance(posed->skin.positions[v], original->skin.positions[v]));
    }
    EXPECT_GT(moved, 0.05);
  }
  for (const char* method : {"lbs", "dqs"}) {
    VISTEL_VALIDATE_OR_SKIP(verdict, dir + "/" + method + ".glb");
    EXPECT_EQ(verdict["errors"], 0) << verdict.dump();
  }
}

TEST(VistelAvatarCli, PoseTheChainFromAVavatarFile) {
  const std::string dir = test::scratchDir();
  Result<AvatarModel> avatar = importGltfAvatar(chainGlb(dir));
  ASSERT_TRUE(avatar.ok());
  ASSERT_TRUE(saveAvatar(*avatar, dir + "/chain.vavatar").ok());
  const test::ToolRun run = test::runTool(
      "pose " + dir + "/chain.vavatar --rest --skinning dqs --out " + dir + "/c.glb", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(importGltfAvatar(dir + "/c.glb").ok());
}

TEST(VistelAvatarCli, DefaultAvatar) {
  const std::string dir = test::scratchDir();
  const test::ToolRun glb = test::runTool("default --out " + dir + "/default.glb", dir);
  ASSERT_EQ(glb.exit_code, 0) << glb.err;
  Result<AvatarModel> avatar = importGltfAvatar(dir + "/default.glb");
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  EXPECT_EQ(avatar->skeleton.jointCount(), 52);
  EXPECT_EQ(avatar->skeleton.names[0], "hips");
  EXPECT_GE(avatar->skin.vertexCount(), 5000);
  EXPECT_LE(avatar->skin.vertexCount(), 15000);

  const test::ToolRun vav = test::runTool("default --out " + dir + "/default.vavatar", dir);
  ASSERT_EQ(vav.exit_code, 0) << vav.err;
  Result<AvatarModel> loaded = loadAvatar(dir + "/default.vavatar");
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_EQ(loaded->skin.vertexCount(), avatar->skin.vertexCount());
  // The .vavatar carries the fitted implicit model (clients deform it).
  ASSERT_TRUE(loaded->implicit.has_value());
  EXPECT_GE(loaded->implicit->primitives.items.size(), 20u);

  VISTEL_VALIDATE_OR_SKIP(verdict, dir + "/default.glb");
  EXPECT_EQ(verdict["errors"], 0) << verdict.dump();
}

TEST(VistelAvatarCli, BadCommandLines) {
  const std::string dir = test::scratchDir();
  const std::string chain = chainGlb(dir);
  test::expectToolFailure(test::runTool("", dir));
  test::expectToolFailure(test::runTool("frobnicate", dir));
  test::expectToolFailure(test::runTool("info", dir), "file");
  test::expectToolFailure(test::runTool("info --json", dir));
  test::expectToolFailure(test::runTool("pose " + chain + " --rest", dir), "--out");
  test::expectToolFailure(test::runTool("pose " + chain + " --out " + dir + "/x.glb", dir),
                          "--rest or --bvh");
  test::expectToolFailure(test::runTool(
      "pose " + chain + " --rest --bvh a.bvh --frame 1 --out " + dir + "/x.glb", dir));
  test::expectToolFailure(
      test::runTool("pose " + chain + " --bvh a.bvh --out " + dir + "/x.glb", dir));
  test::expectToolFailure(
      test::runTool("pose " + chain + " --rest --skinning foo --out " + dir + "/x.glb", dir),
      "foo");
  test::expectToolFailure(
      test::runTool("pose " + chain + " --rest --frame x --out " + dir + "/x.glb", dir));
  test::expectToolFailure(test::runTool("default", dir), "--out");
  test::expectToolFailure(test::runTool("default --out " + dir + "/x.txt", dir),
                          "must end in .glb or .vavatar");
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.glb"));
}

TEST(VistelAvatarCli, BadFiles) {
  const std::string dir = test::scratchDir();
  const std::string chain = chainGlb(dir);
  test::expectToolFailure(test::runTool("info " + dir + "/missing.glb", dir),
                          "missing.glb: no such file");
  test::expectToolFailure(test::runTool("info " + dir, dir), "folder");

  std::ofstream(dir + "/garbage.glb") << "hello, this is not a model";
  test::expectToolFailure(test::runTool("info " + dir + "/garbage.glb", dir),
                          "garbage.glb: not a glTF file");

  std::vector<std::uint8_t> bytes = test::makeChainGltf().file.glb();
  std::ofstream(dir + "/cut.glb", std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), 300);
  test::expectToolFailure(test::runTool("info " + dir + "/cut.glb", dir), "cut.glb: byte 8");

  std::ofstream(dir + "/bad.vavatar") << "VAVATAR garbage";
  test::expectToolFailure(test::runTool("info " + dir + "/bad.vavatar", dir), "bad.vavatar");

  test::expectToolFailure(test::runTool("pose " + chain + " --bvh " + dir +
                                            "/missing.bvh --frame 0 --out " + dir + "/x.glb",
                                        dir),
                          "missing.bvh");
  std::ofstream(dir + "/bad.bvh") << "HIERARCHY\nROOT hips\n{\n";
  test::expectToolFailure(
      test::runTool(
          "pose " + chain + " --bvh " + dir + "/bad.bvh --frame 0 --out " + dir + "/x.glb", dir),
      "bad.bvh");
  test::expectToolFailure(
      test::runTool("pose " + chain + " --rest --out " + dir + "/no/such/dir/x.glb", dir));
}

TEST(VistelAvatarCli, FrameOutOfRange) {
  VISTEL_REQUIRE_SHARED(avatar_path, test::kMakeHumanGlb);
  VISTEL_REQUIRE_SHARED(clip, "mocap/cmu/01_01.bvh");
  const std::string dir = test::scratchDir();
  test::expectToolFailure(test::runTool("pose " + avatar_path + " --bvh " + clip +
                                            " --frame 999999 --out " + dir + "/x.glb",
                                        dir),
                          "frame 999999 out of range");
  test::expectToolFailure(test::runTool(
      "pose " + avatar_path + " --bvh " + clip + " --frame -3 --out " + dir + "/x.glb", dir));
}

}  // namespace
}  // namespace vistel
