// Joint-name maps (common/motion/joint_map.hpp): the canonical list, the TOML format and
// its errors, loading from disk and from the built-in copies, choosing a map.
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/motion/joint_map.hpp"
#include "tests/motion/glb_skeleton.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// A skeleton with these names, in a chain (only the names matter for selection).
Skeleton namedSkeleton(const std::vector<std::string>& names) {
  Skeleton s;
  s.names = names;
  for (std::size_t j = 0; j < names.size(); ++j) s.parents.push_back(static_cast<int>(j) - 1);
  s.rest_local.resize(names.size());
  computeInverseBind(s);
  return s;
}

std::vector<JointMap> loadedMaps(const std::string& dir = "config") {
  Result<std::vector<JointMap>> maps = loadJointMaps(dir);
  EXPECT_TRUE(maps.ok()) << maps.error().message;
  return maps ? *maps : std::vector<JointMap>{};
}

TEST(CanonicalJoints, AreTheFiftyTwoOfTheRules) {
  const auto names = canonicalJoints();
  ASSERT_EQ(names.size(), 52u);
  EXPECT_EQ(names[0], "hips");
  EXPECT_EQ(std::set<std::string_view>(names.begin(), names.end()).size(), 52u);
  for (std::string_view n : {"spine", "chest", "upper_chest", "neck", "head", "l_clavicle",
                             "r_pinky3", "l_thumb1", "r_toes", "l_shin"}) {
    EXPECT_GE(canonicalIndex(n), 0) << n;
  }
  EXPECT_EQ(canonicalIndex("pelvis"), -1);
  // Parents precede children, and the chains are the expected ones.
  const auto parents = canonicalParents();
  ASSERT_EQ(parents.size(), names.size());
  EXPECT_EQ(parents[0], -1);
  for (std::size_t i = 1; i < names.size(); ++i) {
    ASSERT_GE(parents[i], 0) << names[i];
    EXPECT_LT(parents[i], static_cast<int>(i)) << names[i];
  }
  const auto parent_of = [&](std::string_view n) {
    return names[static_cast<std::size_t>(parents[static_cast<std::size_t>(canonicalIndex(n))])];
  };
  EXPECT_EQ(parent_of("l_forearm"), "l_upperarm");
  EXPECT_EQ(parent_of("r_clavicle"), "upper_chest");
  EXPECT_EQ(parent_of("l_index1"), "l_hand");
  EXPECT_EQ(parent_of("r_pinky3"), "r_pinky2");
  EXPECT_EQ(parent_of("l_thigh"), "hips");
  EXPECT_EQ(parent_of("r_toes"), "r_foot");
  EXPECT_EQ(parent_of("head"), "neck");
}

TEST(JointMapFiles, DiskAndBuiltInCopiesAgree) {
  const std::vector<JointMap> disk = loadedMaps("config");
  const std::vector<JointMap> built_in = loadedMaps("no/such/folder");
  std::vector<std::string> names;
  for (const JointMap& m : disk) names.push_back(m.name);
  EXPECT_EQ(names, (std::vector<std::string>{"bandai_gestures", "cmu_01", "cmu_131", "makehuman",
                                             "vistel_default"}));
  ASSERT_EQ(built_in.size(), disk.size());
  for (std::size_t i = 0; i < disk.size(); ++i) {
    EXPECT_EQ(built_in[i].name, disk[i].name);
    EXPECT_EQ(built_in[i].canonical, disk[i].canonical);
    EXPECT_EQ(built_in[i].joint, disk[i].joint);
    EXPECT_NE(built_in[i].source.find("built in"), std::string::npos);
  }
  // The identity map names every canonical joint as itself; the MakeHuman map all 52.
  for (const JointMap& m : disk) {
    if (m.name == "vistel_default") {
      ASSERT_EQ(m.canonical.size(), 52u);
      EXPECT_EQ(m.canonical, m.joint);
    }
    if (m.name == "makehuman") {
      EXPECT_EQ(m.canonical.size(), 52u);
      EXPECT_EQ(m.jointFor("l_forearm"), "lowerarm_l");
      EXPECT_EQ(m.jointFor("r_toes"), "ball_r");
    }
    if (m.name == "cmu_131") {
      EXPECT_EQ(m.jointFor("l_clavicle"), "LeftCollar");
      EXPECT_EQ(m.jointFor("l_upperarm"), "LeftShoulder");
      EXPECT_EQ(m.jointFor("l_hand"), "LeftWrist");
    }
    if (m.name == "cmu_01") {
      EXPECT_EQ(m.jointFor("l_clavicle"), "LeftShoulder");
      EXPECT_EQ(m.jointFor("l_upperarm"), "LeftArm");
    }
    EXPECT_EQ(m.jointFor("no_such_joint"), "");
  }
}

TEST(JointMapParse, ReadsEntriesInCanonicalOrder) {
  Result<JointMap> map = parseJointMap(R"(
name = "mini"
description = "a test"
required = ["hips"]
[joints]
l_hand = "HandL"
hips = "Pelvis"
spine = "Back"
)",
                                       "mini.toml");
  ASSERT_TRUE(map.ok()) << map.error().message;
  EXPECT_EQ(map->name, "mini");
  EXPECT_EQ(map->canonical, (std::vector<std::string>{"hips", "spine", "l_hand"}));
  EXPECT_EQ(map->joint, (std::vector<std::string>{"Pelvis", "Back", "HandL"}));
  EXPECT_EQ(map->required, (std::vector<std::string>{"hips"}));
  // Without a name, the file's stem.
  Result<JointMap> unnamed =
      parseJointMap("required = [\"hips\"]\n[joints]\nhips = \"H\"\n", "dir/family_x.toml");
  ASSERT_TRUE(unnamed.ok()) << unnamed.error().message;
  EXPECT_EQ(unnamed->name, "family_x");
}

TEST(JointMapParse, ErrorsNameTheSourceLineAndReason) {
  const struct {
    const char* text;
    const char* expected;
  } cases[] = {
      {"[joints]\nhips = \"H\"\nelbow = \"E\"\n", "bad.toml:3: [joints].elbow: not a canonical"},
      {"[joints]\nhips = \"H\"\nspine = \"H\"\n",
       "bad.toml:3: [joints].spine: joint 'H' is already mapped from 'hips'"},
      {"[joints]\nhips = 3\n", "bad.toml:2: [joints].hips: the value must be a non-empty string"},
      {"[joints]\nhips = \"\"\n", "bad.toml:2: [joints].hips"},
      {"nmae = \"x\"\n[joints]\nhips = \"H\"\n", "bad.toml:1: unknown key 'nmae'"},
      {"[joints]\nhips = \"H\n", "bad.toml:2:"},
      {"joints = 5\n", "bad.toml:1: 'joints' must be a table"},
      {"required = [\"hips\", \"wing\"]\n[joints]\nhips = \"H\"\n", "bad.toml:1: 'required'"},
      {"[joints]\nhips = \"H\"\n", "bad.toml: required joint 'spine' is not in [joints]"},
      {"name = \"x\"\n", "bad.toml: the map has no [joints] entries"},
  };
  for (const auto& c : cases) {
    Result<JointMap> map = parseJointMap(c.text, "bad.toml");
    ASSERT_FALSE(map.ok()) << c.text;
    EXPECT_EQ(map.error().message.rfind(c.expected, 0), 0u)
        << "got: " << map.error().message << "\nexpected: " << c.expected;
  }
}

TEST(JointMapSelect, PicksEachFamily) {
  const std::vector<JointMap> maps = loadedMaps();
  // CMU 01 and 131 share names (Hips, Head, LeftShoulder...) with different meanings.
  const Skeleton cmu01 =
      namedSkeleton({"Hips",         "LHipJoint",     "LeftUpLeg",    "LeftLeg",      "LeftFoot",
                     "LeftToeBase",  "RHipJoint",     "RightUpLeg",   "RightLeg",     "RightFoot",
                     "RightToeBase", "LowerBack",     "Spine",        "Spine1",       "Neck",
                     "Neck1",        "Head",          "LeftShoulder", "LeftArm",      "LeftForeArm",
                     "LeftHand",     "RightShoulder", "RightArm",     "RightForeArm", "RightHand"});
  const Skeleton cmu131 =
      namedSkeleton({"Hips",      "LHipJoint",   "LeftHip",       "LeftKnee",     "LeftAnkle",
                     "LeftToe",   "RHipJoint",   "RightHip",      "RightKnee",    "RightAnkle",
                     "RightToe",  "lowerback",   "Chest",         "Chest2",       "lowerneck",
                     "Neck",      "Head",        "LeftCollar",    "LeftShoulder", "LeftElbow",
                     "LeftWrist", "RightCollar", "RightShoulder", "RightElbow",   "RightWrist"});
  std::vector<std::string> canonical(canonicalJoints().begin(), canonicalJoints().end());
  const struct {
    const Skeleton skeleton;
    const char* expected;
  } cases[] = {
      {cmu01, "cmu_01"}, {cmu131, "cmu_131"}, {namedSkeleton(canonical), "vistel_default"}};
  for (const auto& c : cases) {
    Result<const JointMap*> map = selectJointMap(maps, c.skeleton);
    ASSERT_TRUE(map.ok()) << map.error().message;
    EXPECT_EQ((*map)->name, c.expected);
  }
  // Nothing fits: the message lists every candidate's coverage.
  Result<const JointMap*> none = selectJointMap(maps, namedSkeleton({"Root", "Hips", "Head"}));
  ASSERT_FALSE(none.ok());
  for (const char* name : {"cmu_01", "cmu_131", "makehuman", "bandai_gestures", "vistel_default"}) {
    EXPECT_NE(none.error().message.find(name), std::string::npos) << none.error().message;
  }
  EXPECT_NE(none.error().message.find("missing required"), std::string::npos);
}

TEST(JointMapSelect, MakeHumanAvatarSkeleton) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  Result<Skeleton> skeleton = test::loadGlbSkeleton(path);
  ASSERT_TRUE(skeleton.ok()) << skeleton.error().message;
  EXPECT_EQ(skeleton->jointCount(), 53);
  const std::vector<JointMap> maps = loadedMaps();
  Result<const JointMap*> map = selectJointMap(maps, *skeleton);
  ASSERT_TRUE(map.ok()) << map.error().message;
  EXPECT_EQ((*map)->name, "makehuman");
  for (const std::string& joint : (*map)->joint) {
    EXPECT_GE(skeleton->find(joint), 0) << joint;
  }
}

}  // namespace
}  // namespace vistel
