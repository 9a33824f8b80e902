// vistel-avatar on rigs no config/skeletons map fits: the shared MakeHuman avatar with its
// joints renamed the Mixamo way and with made-up names. `info` prints the inferred map;
// `pose --bvh` retargets a CMU clip onto the renamed avatar exactly as onto the original.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/base/file.hpp"
#include "common/motion/joint_map.hpp"
#include "tests/gltf/gltf_test_models.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

std::uint32_t readU32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
void appendU32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
  b.insert(b.end(), p, p + 4);
}

// The GLB's JSON and the rest of the file after the JSON chunk.
struct Glb {
  nlohmann::json json;
  std::vector<std::uint8_t> rest;
};

Glb readGlb(const std::string& path) {
  Result<std::vector<std::uint8_t>> bytes = readFileBytes(path, 1u << 28);
  EXPECT_TRUE(bytes.ok()) << path;
  Glb glb;
  if (!bytes || bytes->size() < 20) return glb;
  const std::uint32_t json_len = readU32(*bytes, 12);
  glb.json = nlohmann::json::parse(bytes->begin() + 20, bytes->begin() + 20 + json_len);
  glb.rest.assign(bytes->begin() + 20 + json_len, bytes->end());
  return glb;
}

void writeGlb(const Glb& glb, const std::string& path) {
  std::string text = glb.json.dump();
  while (text.size() % 4 != 0) text += ' ';
  std::vector<std::uint8_t> out;
  appendU32(out, 0x46546C67u);  // "glTF"
  appendU32(out, 2);
  appendU32(out, static_cast<std::uint32_t>(12 + 8 + text.size() + glb.rest.size()));
  appendU32(out, static_cast<std::uint32_t>(text.size()));
  appendU32(out, 0x4E4F534Au);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  out.insert(out.end(), glb.rest.begin(), glb.rest.end());
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
}

// Mixamo's name for a canonical joint ("l_thumb1" -> "mixamorig:LeftHandThumb1").
std::string mixamoFor(const std::string& canonical) {
  static const std::map<std::string, std::string> kNames = {
      {"hips", "Hips"},          {"spine", "Spine"},  {"chest", "Spine1"},
      {"upper_chest", "Spine2"}, {"neck", "Neck"},    {"head", "Head"},
      {"clavicle", "Shoulder"},  {"upperarm", "Arm"}, {"forearm", "ForeArm"},
      {"hand", "Hand"},          {"thigh", "UpLeg"},  {"shin", "Leg"},
      {"foot", "Foot"},          {"toes", "ToeBase"}};
  if (auto it = kNames.find(canonical); it != kNames.end()) return "mixamorig:" + it->second;
  const std::string side = canonical[0] == 'l' ? "Left" : "Right";
  std::string rest = canonical.substr(2);
  if (auto it = kNames.find(rest); it != kNames.end()) return "mixamorig:" + side + it->second;
  rest[0] = static_cast<char>(std::toupper(rest[0]));
  return "mixamorig:" + side + "Hand" + rest;
}

// The shared avatar with every skin joint renamed by `rename(old name)`.
template <class F>
std::string renamedAvatar(const std::string& avatar, const std::string& out, F rename) {
  Glb glb = readGlb(avatar);
  for (auto& node : glb.json["nodes"]) {
    if (node.contains("name")) node["name"] = rename(node["name"].get<std::string>());
  }
  writeGlb(glb, out);
  return out;
}

std::map<std::string, std::string> makehumanToCanonical() {
  Result<std::vector<JointMap>> maps = loadJointMaps("config");
  std::map<std::string, std::string> out;
  if (!maps) return out;
  for (const JointMap& m : *maps) {
    if (m.name != "makehuman") continue;
    for (std::size_t i = 0; i < m.canonical.size(); ++i) out[m.joint[i]] = m.canonical[i];
  }
  return out;
}

TEST(VistelAvatarJointMap, InfoPrintsTheInferredMapForMixamoAndMadeUpNames) {
  VISTEL_REQUIRE_SHARED(avatar, test::kMakeHumanGlb);
  const std::string dir = test::scratchDir();
  const std::map<std::string, std::string> canonical = makehumanToCanonical();
  ASSERT_EQ(canonical.size(), 52u);

  // Mixamo names: every canonical joint from the "mixamo" scheme.
  const std::string mixamo = renamedAvatar(avatar, dir + "/mixamo.glb", [&](const std::string& n) {
    auto it = canonical.find(n);
    return it == canonical.end() ? n : mixamoFor(it->second);
  });
  test::ToolRun run = test::runTool("info --json " + mixamo, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  nlohmann::json info = nlohmann::json::parse(run.out);
  ASSERT_TRUE(info.contains("joint_map")) << run.out;
  EXPECT_EQ(info["joint_map"]["name"], "inferred");
  EXPECT_TRUE(info["joint_map"]["inferred"].get<bool>());
  ASSERT_EQ(info["joint_map"]["joints"].size(), 52u);
  for (const auto& [c, entry] : info["joint_map"]["joints"].items()) {
    EXPECT_EQ(entry["joint"], mixamoFor(c)) << c;
    EXPECT_EQ(entry["from"], "mixamo") << c;
  }

  // Made-up names: all by topology, the same joints as the curated map.
  std::map<std::string, std::string> made_up;  // MakeHuman name -> "bone_N"
  const std::string madeup = renamedAvatar(avatar, dir + "/madeup.glb", [&](const std::string& n) {
    auto [it, added] = made_up.emplace(n, fmt::format("bone_{}", made_up.size()));
    return it->second;
  });
  run = test::runTool("info --json " + madeup, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  info = nlohmann::json::parse(run.out);
  ASSERT_EQ(info["joint_map"]["joints"].size(), 52u) << run.out;
  for (const auto& [mh, c] : canonical) {
    const auto& entry = info["joint_map"]["joints"][c];
    EXPECT_EQ(entry["joint"], made_up.at(mh)) << c << " (curated " << mh << ")";
    EXPECT_EQ(entry["from"], "topology") << c;
  }

  // The implicit model builds on the made-up names as on the original (30 primitives).
  run = test::runTool(fmt::format("build {} -o {}/madeup.vavatar", madeup, dir), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(30 from the map"), std::string::npos) << run.out;

  // The text form names the map and each joint's origin.
  run = test::runTool("info " + mixamo, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("map: inferred"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("mixamorig:LeftHandThumb1"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("[mixamo]"), std::string::npos) << run.out;
  // The original avatar still uses its curated map.
  run = test::runTool("info " + avatar, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("map: makehuman"), std::string::npos) << run.out;
}

TEST(VistelAvatarJointMap, NoNeckRigByTopologyBuildsWithoutTheNeckPrimitive) {
  VISTEL_REQUIRE_SHARED(avatar, test::kMakeHumanGlb);
  const std::string dir = test::scratchDir();
  // The head moved from neck_01 to spine_03 (rest transforms are translations only, so its
  // translation gains the neck's), neck_01 left as a short leaf; then made-up names.
  Glb glb = readGlb(avatar);
  nlohmann::json& nodes = glb.json["nodes"];
  const auto index = [&](const std::string& name) {
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (nodes[i].value("name", "") == name) return static_cast<int>(i);
    }
    return -1;
  };
  const int neck = index("neck_01"), head = index("head"), top = index("spine_03");
  ASSERT_GE(neck, 0);
  ASSERT_GE(head, 0);
  ASSERT_GE(top, 0);
  ASSERT_TRUE(nodes[neck].contains("translation") && nodes[head].contains("translation"));
  for (int k = 0; k < 3; ++k) {
    nodes[head]["translation"][k] =
        nodes[head]["translation"][k].get<double>() + nodes[neck]["translation"][k].get<double>();
  }
  nodes[neck].erase("children");
  nodes[top]["children"].push_back(head);
  for (std::size_t i = 0; i < nodes.size(); ++i) nodes[i]["name"] = fmt::format("n{}", i);
  const std::string path = dir + "/noneck.glb";
  writeGlb(glb, path);

  test::ToolRun run = test::runTool("info --json " + path, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json info = nlohmann::json::parse(run.out);
  const nlohmann::json& joints = info["joint_map"]["joints"];
  EXPECT_FALSE(joints.contains("neck")) << joints.dump();
  ASSERT_TRUE(joints.contains("head")) << joints.dump();
  EXPECT_EQ(joints["head"]["joint"], fmt::format("n{}", head));
  EXPECT_EQ(joints.size(), 51u);
  run = test::runTool(fmt::format("build {} -o {}/noneck.vavatar", path, dir), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("(29 from the map"), std::string::npos) << run.out;
  EXPECT_NE((run.out + run.err).find("neck"), std::string::npos) << run.out << run.err;
}

TEST(VistelAvatarJointMap, InfoOnANonHumanoidSaysWhyThereIsNoMap) {
  const std::string dir = test::scratchDir();
  const std::string path = dir + "/chain.glb";
  const std::vector<std::uint8_t> bytes = test::makeChainGltf().file.glb();
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  test::ToolRun run = test::runTool("info " + path, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("joint map: none: cannot map"), std::string::npos) << run.out;
  run = test::runTool("info --json " + path, dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json info = nlohmann::json::parse(run.out);
  EXPECT_NE(info["joint_map"]["error"].get<std::string>().find("hips"), std::string::npos)
      << run.out;
}

TEST(VistelAvatarJointMap, CmuClipRetargetsOntoMixamoNamedAvatarAsOntoTheOriginal) {
  VISTEL_REQUIRE_SHARED(avatar, test::kMakeHumanGlb);
  VISTEL_REQUIRE_SHARED(clip, "mocap/cmu/131_01.bvh");
  const std::string dir = test::scratchDir();
  const std::map<std::string, std::string> canonical = makehumanToCanonical();
  const std::string mixamo = renamedAvatar(avatar, dir + "/mixamo.glb", [&](const std::string& n) {
    auto it = canonical.find(n);
    return it == canonical.end() ? n : mixamoFor(it->second);
  });
  test::ToolRun a = test::runTool(
      fmt::format("pose {} --bvh {} --frame 200 --out {}/a.glb", avatar, clip, dir), dir);
  ASSERT_EQ(a.exit_code, 0) << a.err;
  test::ToolRun b = test::runTool(
      fmt::format("pose {} --bvh {} --frame 200 --out {}/b.glb", mixamo, clip, dir), dir);
  ASSERT_EQ(b.exit_code, 0) << b.err;
  // The same posed vertices: the binary chunks are equal.
  const Glb ga = readGlb(dir + "/a.glb");
  const Glb gb = readGlb(dir + "/b.glb");
  ASSERT_FALSE(ga.rest.empty());
  EXPECT_TRUE(ga.rest == gb.rest);
}

}  // namespace
}  // namespace vistel
