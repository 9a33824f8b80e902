// Joint-map inference (common/motion/auto_joint_map.hpp): synthetic rigs per naming
// scheme, rigs mapped by topology alone (Z-up, no hands, made-up names), mirrored names,
// non-humanoids refused, and the shared clips and avatar mapped as their curated maps.
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/motion/auto_joint_map.hpp"
#include "common/motion/bvh.hpp"
#include "tests/motion/glb_skeleton.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// A humanoid in T-pose, Y-up metres, facing +Z, its left at +X: roles (canonical names,
// plus "head_end" and "l_toe_end"/"r_toe_end" tips), parents and rest offsets.
struct Bone {
  std::string role;
  std::string parent;
  glm::vec3 offset;
};

std::vector<Bone> humanoidBones(bool hands = true, bool clavicles = true, bool upper_chest = true,
                                bool tips = true) {
  std::vector<Bone> b = {{"hips", "", {0.0f, 1.0f, 0.0f}},
                         {"spine", "hips", {0.0f, 0.1f, 0.0f}},
                         {"chest", "spine", {0.0f, 0.12f, 0.0f}}};
  const std::string top = upper_chest ? "upper_chest" : "chest";
  if (upper_chest) b.push_back({"upper_chest", "chest", {0.0f, 0.12f, 0.0f}});
  b.push_back({"neck", top, {0.0f, 0.15f, 0.0f}});
  b.push_back({"head", "neck", {0.0f, 0.1f, 0.0f}});
  if (tips) b.push_back({"head_end", "head", {0.0f, 0.2f, 0.0f}});
  for (const char* s : {"l_", "r_"}) {
    const float x = s[0] == 'l' ? 1.0f : -1.0f;
    const std::string p(s);
    if (clavicles) b.push_back({p + "clavicle", top, {0.05f * x, 0.1f, 0.0f}});
    b.push_back({p + "upperarm",
                 clavicles ? p + "clavicle" : top,
                 {(clavicles ? 0.12f : 0.17f) * x, clavicles ? 0.0f : 0.1f, 0.0f}});
    b.push_back({p + "forearm", p + "upperarm", {0.28f * x, 0.0f, 0.0f}});
    b.push_back({p + "hand", p + "forearm", {0.25f * x, 0.0f, 0.0f}});
    if (hands) {
      const struct {
        const char* name;
        glm::vec3 base;
        glm::vec3 step;
      } fingers[] = {{"thumb", {0.02f, -0.01f, 0.03f}, {0.03f, 0.0f, 0.02f}},
                     {"index", {0.08f, 0.0f, 0.025f}, {0.03f, 0.0f, 0.0f}},
                     {"middle", {0.085f, 0.0f, 0.005f}, {0.032f, 0.0f, 0.0f}},
                     {"ring", {0.08f, 0.0f, -0.015f}, {0.03f, 0.0f, 0.0f}},
                     {"pinky", {0.07f, 0.0f, -0.035f}, {0.022f, 0.0f, 0.0f}}};
      for (const auto& f : fingers) {
        const glm::vec3 mirror(x, 1.0f, 1.0f);
        b.push_back({p + f.name + "1", p + "hand", f.base * mirror});
        b.push_back({p + f.name + "2", p + f.name + "1", f.step * mirror});
        b.push_back({p + f.name + "3", p + f.name + "2", f.step * mirror});
      }
    }
    b.push_back({p + "thigh", "hips", {0.09f * x, -0.05f, 0.0f}});
    b.push_back({p + "shin", p + "thigh", {0.0f, -0.42f, 0.0f}});
    b.push_back({p + "foot", p + "shin", {0.0f, -0.42f, 0.0f}});
    b.push_back({p + "toes", p + "foot", {0.0f, -0.06f, 0.12f}});
    if (tips) b.push_back({p + "toe_end", p + "toes", {0.0f, 0.0f, 0.05f}});
  }
  return b;
}

// Builds a skeleton from bones, naming each role with `name` (empty: drop the joint, which
// must be a leaf). root_name non-empty adds a root node above the hips with that rotation;
// z_up_cm turns the rest offsets into Z-up centimetres (x, y, z) -> 100 (x, -z, y).
Skeleton makeSkeleton(const std::vector<Bone>& bones,
                      const std::function<std::string(const std::string&)>& name,
                      bool z_up_cm = false, const std::string& root_name = "",
                      glm::quat root_rotation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f)) {
  Skeleton s;
  std::map<std::string, int> index;
  if (!root_name.empty()) {
    s.names.push_back(root_name);
    s.parents.push_back(kNoParent);
    Transform t;
    t.rotation = root_rotation;
    s.rest_local.push_back(t);
  }
  for (const Bone& bone : bones) {
    const std::string n = name(bone.role);
    if (n.empty()) continue;
    Transform t;
    t.translation =
        z_up_cm ? 100.0f * glm::vec3(bone.offset.x, -bone.offset.z, bone.offset.y) : bone.offset;
    index[bone.role] = s.jointCount();
    s.names.push_back(n);
    s.parents.push_back(bone.parent.empty() ? (root_name.empty() ? kNoParent : 0)
                                            : index.at(bone.parent));
    s.rest_local.push_back(t);
  }
  computeInverseBind(s);
  return s;
}

// Mixamo: "mixamorig:" + Hips, Spine, Spine1, Spine2, Neck, Head, LeftShoulder, LeftArm...
std::string mixamoName(const std::string& role) {
  static const std::map<std::string, std::string> kCentre = {
      {"hips", "Hips"}, {"spine", "Spine"}, {"chest", "Spine1"},        {"upper_chest", "Spine2"},
      {"neck", "Neck"}, {"head", "Head"},   {"head_end", "HeadTop_End"}};
  static const std::map<std::string, std::string> kLimb = {
      {"clavicle", "Shoulder"}, {"upperarm", "Arm"}, {"forearm", "ForeArm"},
      {"hand", "Hand"},         {"thigh", "UpLeg"},  {"shin", "Leg"},
      {"foot", "Foot"},         {"toes", "ToeBase"}, {"toe_end", "Toe_End"}};
  if (auto it = kCentre.find(role); it != kCentre.end()) return "mixamorig:" + it->second;
  const std::string side = role[0] == 'l' ? "Left" : "Right";
  const std::string rest = role.substr(2);
  if (auto it = kLimb.find(rest); it != kLimb.end()) return "mixamorig:" + side + it->second;
  std::string finger = rest;  // "thumb1" -> "HandThumb1"
  finger[0] = static_cast<char>(std::toupper(finger[0]));
  return "mixamorig:" + side + "Hand" + finger;
}

std::string vrmName(const std::string& role) {
  static const std::map<std::string, std::string> kCentre = {
      {"hips", "hips"}, {"spine", "spine"}, {"chest", "chest"}, {"upper_chest", "upperChest"},
      {"neck", "neck"}, {"head", "head"},   {"head_end", ""}};
  static const std::map<std::string, std::string> kLimb = {{"clavicle", "Shoulder"},
                                                           {"upperarm", "UpperArm"},
                                                           {"forearm", "LowerArm"},
                                                           {"hand", "Hand"},
                                                           {"thigh", "UpperLeg"},
                                                           {"shin", "LowerLeg"},
                                                           {"foot", "Foot"},
                                                           {"toes", "Toes"},
                                                           {"toe_end", ""},
                                                           {"thumb1", "ThumbMetacarpal"},
                                                           {"thumb2", "ThumbProximal"},
                                                           {"thumb3", "ThumbDistal"}};
  if (auto it = kCentre.find(role); it != kCentre.end()) return it->second;
  const std::string side = role[0] == 'l' ? "left" : "right";
  const std::string rest = role.substr(2);
  if (auto it = kLimb.find(rest); it != kLimb.end()) {
    return it->second.empty() ? std::string() : side + it->second;
  }
  std::string finger = rest.substr(0, rest.size() - 1);
  if (finger == "pinky") finger = "little";
  finger[0] = static_cast<char>(std::toupper(finger[0]));
  const char* phalanx[] = {"Proximal", "Intermediate", "Distal"};
  return side + finger + phalanx[rest.back() - '1'];
}

std::string unrealName(const std::string& role) {
  static const std::map<std::string, std::string> kCentre = {
      {"hips", "pelvis"},    {"spine", "spine_01"},
      {"chest", "spine_02"}, {"upper_chest", "spine_03"},
      {"neck", "neck_01"},   {"head", "head"},
      {"head_end", ""}};
  static const std::map<std::string, std::string> kLimb = {
      {"clavicle", "clavicle"}, {"upperarm", "upperarm"}, {"forearm", "lowerarm"},
      {"hand", "hand"},         {"thigh", "thigh"},       {"shin", "calf"},
      {"foot", "foot"},         {"toes", "ball"},         {"toe_end", ""}};
  if (auto it = kCentre.find(role); it != kCentre.end()) return it->second;
  const std::string side = role[0] == 'l' ? "_l" : "_r";
  const std::string rest = role.substr(2);
  if (auto it = kLimb.find(rest); it != kLimb.end()) {
    return it->second.empty() ? std::string() : it->second + side;
  }
  return fmt::format("{}_0{}{}", rest.substr(0, rest.size() - 1), rest.back(), side);
}

std::string rigifyName(const std::string& role) {
  static const std::map<std::string, std::string> kCentre = {{"hips", "DEF-spine"},
                                                             {"spine", "DEF-spine.001"},
                                                             {"chest", "DEF-spine.002"},
                                                             {"upper_chest", "DEF-spine.003"},
                                                             {"neck", "DEF-spine.004"},
                                                             {"head", "DEF-spine.006"},
                                                             {"head_end", ""}};
  static const std::map<std::string, std::string> kLimb = {
      {"clavicle", "shoulder"}, {"upperarm", "upper_arm"}, {"forearm", "forearm"},
      {"hand", "hand"},         {"thigh", "thigh"},        {"shin", "shin"},
      {"foot", "foot"},         {"toes", "toe"},           {"toe_end", ""}};
  if (auto it = kCentre.find(role); it != kCentre.end()) return it->second;
  const std::string side = role[0] == 'l' ? ".L" : ".R";
  const std::string rest = role.substr(2);
  if (auto it = kLimb.find(rest); it != kLimb.end()) {
    return it->second.empty() ? std::string() : "DEF-" + it->second + side;
  }
  const std::string finger = rest.substr(0, rest.size() - 1);
  return fmt::format("DEF-{}{}.0{}{}", finger == "thumb" ? "" : "f_", finger, rest.back(), side);
}

// Expects every canonical role of `bones` to map to the joint `name` gives it.
void expectMapsRoles(const JointMapChoice& choice, const std::vector<Bone>& bones,
                     const std::function<std::string(const std::string&)>& name,
                     const std::string& label) {
  for (const Bone& bone : bones) {
    if (canonicalIndex(bone.role) < 0) continue;
    EXPECT_EQ(choice.map.jointFor(bone.role), name(bone.role)) << label << ": " << bone.role;
  }
  for (std::string_view r : kDefaultRequiredJoints) {
    EXPECT_FALSE(choice.map.jointFor(r).empty()) << label << ": " << r;
  }
}

TEST(InferJointMap, EveryNamingScheme) {
  const std::vector<Bone> bones = humanoidBones();
  const struct {
    const char* scheme;
    std::string (*name)(const std::string&);
  } cases[] = {
      {"mixamo", mixamoName}, {"vrm", vrmName}, {"unreal", unrealName}, {"rigify", rigifyName}};
  for (const auto& c : cases) {
    for (bool z_up : {false, true}) {
      const Skeleton s = makeSkeleton(bones, c.name, z_up);
      Result<JointMapChoice> choice = inferJointMap(s);
      ASSERT_TRUE(choice.ok()) << c.scheme << ": " << choice.error().message;
      EXPECT_TRUE(choice->inferred);
      EXPECT_EQ(choice->map.name, "inferred");
      EXPECT_EQ(choice->map.canonical.size(), 52u) << c.scheme;
      expectMapsRoles(*choice, bones, c.name, fmt::format("{} z_up={}", c.scheme, z_up));
      for (const std::string& origin : choice->origin) EXPECT_EQ(origin, c.scheme);
      EXPECT_TRUE(choice->notes.empty()) << c.scheme;
    }
  }
}

TEST(InferJointMap, ArmatureAndSeparatorVariants) {
  // "Armature|" prefixes, upper case, and VRM 0.x thumbs (Proximal/Intermediate/Distal).
  const std::vector<Bone> bones = humanoidBones();
  const auto vrm0 = [](const std::string& role) {
    std::string n = vrmName(role);
    if (n.ends_with("ThumbProximal")) n.replace(n.size() - 8, 8, "Intermediate");
    if (n.ends_with("ThumbMetacarpal")) n.replace(n.size() - 10, 10, "Proximal");
    return n.empty() ? n : "Armature|" + n;
  };
  Result<JointMapChoice> choice = inferJointMap(makeSkeleton(bones, vrm0));
  ASSERT_TRUE(choice.ok()) << choice.error().message;
  expectMapsRoles(*choice, bones, vrm0, "vrm 0.x");
}

// Made-up names ("b00", "b01"...) that no scheme knows.
std::function<std::string(const std::string&)> madeUpNames(const std::vector<Bone>& bones) {
  auto order = std::make_shared<std::map<std::string, std::string>>();
  for (std::size_t i = 0; i < bones.size(); ++i) (*order)[bones[i].role] = fmt::format("b{:02}", i);
  return [order](const std::string& role) { return order->at(role); };
}

TEST(InferJointMap, NineteenJointsNoHandsUnderZUpRootByTopology) {
  // hips, spine, chest, neck, head, 2 x (upper arm, forearm, hand), 2 x (thigh, shin, foot,
  // toes): 19 joints, no names any scheme knows, under a root node whose rotation turns the
  // Y-up joint offsets into a Z-up model space.
  const std::vector<Bone> bones = humanoidBones(false, false, false, false);
  ASSERT_EQ(bones.size(), 19u);
  const auto names = madeUpNames(bones);
  const glm::quat y_to_z = glm::angleAxis(glm::radians(90.0f), glm::vec3(1.0f, 0.0f, 0.0f));
  const Skeleton s = makeSkeleton(bones, names, false, "SceneRoot", y_to_z);
  ASSERT_EQ(s.jointCount(), 20);
  Result<JointMapChoice> choice = inferJointMap(s);
  ASSERT_TRUE(choice.ok()) << choice.error().message;
  expectMapsRoles(*choice, bones, names, "topology");
  EXPECT_EQ(choice->map.canonical.size(), 19u);
  for (const std::string& origin : choice->origin) EXPECT_EQ(origin, "topology");
  // And in Z-up centimetres without toes, where forward falls back to -Y.
  std::vector<Bone> no_toes;
  for (const Bone& b : bones) {
    if (!b.role.ends_with("toes")) no_toes.push_back(b);
  }
  const auto names2 = madeUpNames(no_toes);
  Result<JointMapChoice> choice2 = inferJointMap(makeSkeleton(no_toes, names2, true));
  ASSERT_TRUE(choice2.ok()) << choice2.error().message;
  expectMapsRoles(*choice2, no_toes, names2, "topology, Z-up cm, no toes");
}

TEST(InferJointMap, FullRigWithMadeUpNamesIncludingFingers) {
  const std::vector<Bone> bones = humanoidBones();
  const auto names = madeUpNames(bones);
  for (bool z_up : {false, true}) {
    Result<JointMapChoice> choice = inferJointMap(makeSkeleton(bones, names, z_up));
    ASSERT_TRUE(choice.ok()) << choice.error().message;
    expectMapsRoles(*choice, bones, names, fmt::format("topology z_up={}", z_up));
  }
}

TEST(InferJointMap, MirroredNamesKeepTheNamesAndSaySo) {
  // The joints at +X (the body's left, facing +Z by the toes) are named "Right...".
  const std::vector<Bone> bones = humanoidBones();
  const auto mirrored = [](const std::string& role) {
    std::string n = mixamoName(role);
    if (n.find("Left") != std::string::npos) return n.replace(n.find("Left"), 4, "Right");
    if (n.find("Right") != std::string::npos) return n.replace(n.find("Right"), 5, "Left");
    return n;
  };
  Result<JointMapChoice> choice = inferJointMap(makeSkeleton(bones, mirrored));
  ASSERT_TRUE(choice.ok()) << choice.error().message;
  EXPECT_EQ(choice->map.jointFor("l_upperarm"), "mixamorig:LeftArm");
  EXPECT_EQ(choice->map.jointFor("r_thigh"), "mixamorig:RightUpLeg");
  ASSERT_EQ(choice->notes.size(), 1u);
  EXPECT_NE(choice->notes[0].find("right side left"), std::string::npos) << choice->notes[0];
}

// Found by fuzz_auto_joint_map: legs were counted back from the end, and toes only where
// the last bone ran within 60 degrees of horizontal, so a toe bone pointing down and forward
// made the toes the foot and the shin the thigh. The knee and ankle are now where the two
// longest consecutive bones end. And topology fills what the names leave with the names'
// sides, also on a mirrored rig.
TEST(InferJointMap, SlantedToesOnOneLegAndAnUnnamedShin) {
  std::vector<Bone> bones;
  for (Bone b : humanoidBones(false, true, true, false)) {
    if (b.role == "r_toes") continue;                          // toes on one leg only
    if (b.role == "l_toes") b.offset = {0.0f, -0.08f, 0.10f};  // 39 degrees below horizontal
    bones.push_back(b);
  }
  const auto topo = madeUpNames(bones);
  Result<JointMapChoice> by_topology = inferJointMap(makeSkeleton(bones, topo));
  ASSERT_TRUE(by_topology.ok()) << by_topology.error().message;
  expectMapsRoles(*by_topology, bones, topo, "topology");

  const auto unnamed_shin = [](const std::string& role) {
    return role == "l_shin" ? std::string("joint_17") : mixamoName(role);
  };
  Result<JointMapChoice> mixed = inferJointMap(makeSkeleton(bones, unnamed_shin));
  ASSERT_TRUE(mixed.ok()) << mixed.error().message;
  expectMapsRoles(*mixed, bones, unnamed_shin, "names and topology");

  const auto mirrored_unnamed_shin = [](const std::string& role) {
    if (role == "l_shin") return std::string("joint_17");
    std::string n = mixamoName(role);
    if (n.find("Left") != std::string::npos) return n.replace(n.find("Left"), 4, "Right");
    if (n.find("Right") != std::string::npos) return n.replace(n.find("Right"), 5, "Left");
    return n;
  };
  Result<JointMapChoice> mirrored = inferJointMap(makeSkeleton(bones, mirrored_unnamed_shin));
  ASSERT_TRUE(mirrored.ok()) << mirrored.error().message;
  // The names' left leg is the pose's right: its shin (named) and thigh; the pose's left
  // shin, unnamed, goes with the names' right leg.
  EXPECT_EQ(mirrored->map.jointFor("l_thigh"), "mixamorig:LeftUpLeg");
  EXPECT_EQ(mirrored->map.jointFor("r_thigh"), "mixamorig:RightUpLeg");
  EXPECT_EQ(mirrored->map.jointFor("r_shin"), "joint_17");
}

TEST(InferJointMap, NonHumanoidsAreRefusedNamingWhatIsMissing) {
  // A snake: one chain.
  Skeleton snake;
  for (int j = 0; j < 12; ++j) {
    snake.names.push_back(fmt::format("seg{}", j));
    snake.parents.push_back(j - 1);
    Transform t;
    t.translation = glm::vec3(0.0f, 0.0f, j == 0 ? 0.0f : 0.2f);
    snake.rest_local.push_back(t);
  }
  computeInverseBind(snake);
  Result<JointMapChoice> s = inferJointMap(snake);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("hips"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("never forks"), std::string::npos) << s.error().message;

  // A quadruped: pelvis -> spine forward (+Z) to the shoulders (neck, two front legs), two
  // hind legs down, a tail back.
  const std::vector<Bone> dog = {
      {"pelvis", "", {0.0f, 0.6f, 0.0f}},      {"back1", "pelvis", {0.0f, 0.0f, 0.2f}},
      {"back2", "back1", {0.0f, 0.0f, 0.2f}},  {"neck", "back2", {0.0f, 0.1f, 0.1f}},
      {"skull", "neck", {0.0f, 0.1f, 0.1f}},   {"fl1", "back2", {0.1f, -0.1f, 0.0f}},
      {"fl2", "fl1", {0.0f, -0.25f, 0.0f}},    {"fl3", "fl2", {0.0f, -0.25f, 0.0f}},
      {"fr1", "back2", {-0.1f, -0.1f, 0.0f}},  {"fr2", "fr1", {0.0f, -0.25f, 0.0f}},
      {"fr3", "fr2", {0.0f, -0.25f, 0.0f}},    {"hl1", "pelvis", {0.1f, -0.1f, 0.0f}},
      {"hl2", "hl1", {0.0f, -0.25f, 0.0f}},    {"hl3", "hl2", {0.0f, -0.25f, 0.0f}},
      {"hr1", "pelvis", {-0.1f, -0.1f, 0.0f}}, {"hr2", "hr1", {0.0f, -0.25f, 0.0f}},
      {"hr3", "hr2", {0.0f, -0.25f, 0.0f}},    {"tail1", "pelvis", {0.0f, 0.0f, -0.2f}},
      {"tail2", "tail1", {0.0f, 0.0f, -0.2f}}};
  Result<JointMapChoice> q =
      inferJointMap(makeSkeleton(dog, [](const std::string& r) { return r; }));
  ASSERT_FALSE(q.ok());
  for (const char* joint : {"l_thigh", "l_shin", "r_thigh", "r_shin"}) {
    EXPECT_NE(q.error().message.find(joint), std::string::npos) << q.error().message;
  }
  EXPECT_NE(q.error().message.find("no legs"), std::string::npos) << q.error().message;
}

TEST(ChooseJointMap, ConfigMapsWinAndInferenceFillsIn) {
  Result<std::vector<JointMap>> maps = loadJointMaps("config");
  ASSERT_TRUE(maps.ok()) << maps.error().message;
  // The MakeHuman-named synthetic rig fits config/skeletons/makehuman.toml.
  const std::vector<Bone> bones = humanoidBones();
  Result<JointMapChoice> mh = chooseJointMap(*maps, makeSkeleton(bones, unrealName));
  ASSERT_TRUE(mh.ok()) << mh.error().message;
  EXPECT_FALSE(mh->inferred);
  EXPECT_EQ(mh->map.name, "makehuman");
  EXPECT_EQ(mh->origin.front(), "makehuman");
  // Mixamo fits none of them: inferred.
  Result<JointMapChoice> mx = chooseJointMap(*maps, makeSkeleton(bones, mixamoName));
  ASSERT_TRUE(mx.ok()) << mx.error().message;
  EXPECT_TRUE(mx->inferred);
  const std::string text = describeJointMapChoice(*mx);
  EXPECT_NE(text.find("map: inferred"), std::string::npos) << text;
  EXPECT_NE(text.find("mixamorig:LeftForeArm"), std::string::npos) << text;
  // Nothing fits and nothing can be inferred: both reasons.
  Skeleton three;
  three.names = {"Root", "Hips", "Head"};
  three.parents = {-1, 0, 1};
  three.rest_local.resize(3);
  computeInverseBind(three);
  Result<JointMapChoice> none = chooseJointMap(*maps, three);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().message.find("cannot map"), std::string::npos);
  EXPECT_NE(none.error().message.find("no joint map fits"), std::string::npos);
}

// The curated map `name` and what inference gives, on the skeleton as it is and on the
// skeleton with every joint renamed "bNN" (topology alone): every entry agrees.
void expectInferenceMatchesCurated(const Skeleton& skeleton, const std::string& map_name,
                                   bool check_topology = true) {
  Result<std::vector<JointMap>> maps = loadJointMaps("config");
  ASSERT_TRUE(maps.ok()) << maps.error().message;
  const JointMap* curated = nullptr;
  std::vector<JointMap> others;
  for (const JointMap& m : *maps) {
    if (m.name == map_name) {
      curated = &m;
    } else {
      others.push_back(m);
    }
  }
  ASSERT_NE(curated, nullptr) << map_name;
  Result<JointMapChoice> by_names = chooseJointMap(others, skeleton);
  ASSERT_TRUE(by_names.ok()) << map_name << ": " << by_names.error().message;
  EXPECT_TRUE(by_names->inferred);
  for (std::size_t i = 0; i < curated->canonical.size(); ++i) {
    EXPECT_EQ(by_names->map.jointFor(curated->canonical[i]), curated->joint[i])
        << map_name << " names: " << curated->canonical[i];
  }
  Skeleton renamed = skeleton;
  for (int j = 0; j < renamed.jointCount(); ++j) {
    renamed.names[static_cast<std::size_t>(j)] = fmt::format("b{:02}", j);
  }
  if (!check_topology) return;
  Result<JointMapChoice> by_topology = inferJointMap(renamed);
  ASSERT_TRUE(by_topology.ok()) << map_name << ": " << by_topology.error().message;
  for (std::size_t i = 0; i < curated->canonical.size(); ++i) {
    const std::string& c = curated->canonical[i];
    const int j = skeleton.find(curated->joint[i]);
    EXPECT_EQ(by_topology->map.jointFor(c), fmt::format("b{:02}", j))
        << map_name << " topology: " << c << " (curated " << curated->joint[i] << ")";
  }
}

TEST(InferJointMap, SharedClipsMatchTheirCuratedMaps) {
  const struct {
    const char* path;
    const char* map;
  } clips[] = {{"mocap/cmu/01_01.bvh", "cmu_01"},
               {"mocap/cmu/131_01.bvh", "cmu_131"},
               {"mocap/cmu/scaled_131_03.bvh", "cmu_131"},
               {"mocap/gestures/dataset-1_bow_normal_001.bvh", "bandai_gestures"}};
  for (const auto& c : clips) {
    VISTEL_REQUIRE_SHARED(path, c.path);
    Result<MotionClip> clip = loadBvh(path);
    ASSERT_TRUE(clip.ok()) << clip.error().message;
    SCOPED_TRACE(c.path);
    // The Bandai clips' zero pose lays every bone along its parent's +X (not a standing
    // pose), so only their names can map them.
    expectInferenceMatchesCurated(clipSkeleton(*clip), c.map,
                                  std::string(c.map) != "bandai_gestures");
  }
}

TEST(InferJointMap, SharedMakeHumanAvatarMatchesItsCuratedMap) {
  VISTEL_REQUIRE_SHARED(path, "avatars/makehuman_game_engine.glb");
  Result<Skeleton> skeleton = test::loadGlbSkeleton(path);
  ASSERT_TRUE(skeleton.ok()) << skeleton.error().message;
  expectInferenceMatchesCurated(*skeleton, "makehuman");
}

}  // namespace
}  // namespace vistel
