// libFuzzer target: inferJointMap (common/motion/auto_joint_map.hpp) on skeletons a hostile
// or broken file can give: any names, any parents that precede their children, any rest
// offsets (zero, huge, mirrored), any depth.
//
// Input: a joint count byte (1..96 joints), then per joint: a parent byte (taken modulo the
// joint's index; the root has none), a name byte (an index into a vocabulary of names from
// every naming scheme, odd spellings and junk, plus a suffix that keeps names unique), and
// three offset bytes (signed, scaled by a per-input unit byte); a name already taken gets
// primes appended.
// Properties: nothing crashes; a map it returns names only joints the skeleton has, each at
// most once, and maps each canonical joint at most once, with one origin per entry and
// every required joint present; a refusal says why.
#include <array>
#include <cstdint>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "common/motion/auto_joint_map.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace vistel {
namespace {

using fuzz::check;

constexpr std::array<const char*, 48> kNames = {"Hips",
                                                "Spine",
                                                "Spine1",
                                                "Spine2",
                                                "Neck",
                                                "Head",
                                                "LeftShoulder",
                                                "LeftArm",
                                                "LeftForeArm",
                                                "LeftHand",
                                                "RightArm",
                                                "RightForeArm",
                                                "RightHand",
                                                "LeftUpLeg",
                                                "LeftLeg",
                                                "LeftFoot",
                                                "LeftToeBase",
                                                "RightUpLeg",
                                                "RightLeg",
                                                "RightFoot",
                                                "mixamorig:Hips",
                                                "pelvis",
                                                "spine_01",
                                                "upperarm_l",
                                                "lowerarm_r",
                                                "thigh_l",
                                                "calf_r",
                                                "ball_l",
                                                "DEF-spine.001",
                                                "upper_arm.L",
                                                "shin.R",
                                                "hips",
                                                "upperChest",
                                                "leftUpperArm",
                                                "rightLowerLeg",
                                                "leftThumbProximal",
                                                "LHipJoint",
                                                "LowerBack",
                                                "Armature|Head",
                                                "",
                                                "\xE2\x80\xAE",
                                                "L",
                                                "R",
                                                ".L",
                                                "_l",
                                                "joint",
                                                "bone",
                                                "\xff\xfe"};

struct Reader {
  std::span<const std::uint8_t> in;
  std::size_t at = 0;
  std::uint8_t u8() { return at < in.size() ? in[at++] : 0; }
};

Skeleton skeletonFrom(std::span<const std::uint8_t> data) {
  Reader r{data};
  const int n = 1 + r.u8() % 96;
  const float unit = 0.001f * static_cast<float>(1 + r.u8());  // metres per offset step
  Skeleton s;
  for (int j = 0; j < n; ++j) {
    const int parent = j == 0 ? kNoParent : r.u8() % j;
    s.names.emplace_back(kNames[r.u8() % kNames.size()]);
    s.parents.push_back(parent);
    Transform t;
    const auto x = static_cast<std::int8_t>(r.u8());  // (in order: arguments are not)
    const auto y = static_cast<std::int8_t>(r.u8());
    const auto z = static_cast<std::int8_t>(r.u8());
    t.translation = glm::vec3(x, y, z) * unit;
    s.rest_local.push_back(t);
  }
  // Names must be unique for a valid skeleton: drop repeats by suffixing.
  std::set<std::string> seen;
  for (std::size_t j = 0; j < s.names.size(); ++j) {
    while (!seen.insert(s.names[j]).second) s.names[j] += "'";
  }
  computeInverseBind(s);
  return s;
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  // A Mixamo-named humanoid: hips, spine chain, neck/head, two arms, two legs.
  std::vector<std::uint8_t> mixamo = {19, 10};  // 20 joints
  const auto add = [&](std::uint8_t parent, std::uint8_t name, int x, int y, int z) {
    mixamo.insert(mixamo.end(), {parent, name, static_cast<std::uint8_t>(x),
                                 static_cast<std::uint8_t>(y), static_cast<std::uint8_t>(z)});
  };
  // (joint 0's parent byte is not read: the first two bytes after the header are its name
  // and offset)
  mixamo.insert(mixamo.end(), {0, 0, 100, 0});                                  // 0 Hips
  add(0, 1, 0, 10, 0);                                                          // 1 Spine
  add(1, 2, 0, 10, 0);                                                          // 2 Spine1
  add(2, 3, 0, 10, 0);                                                          // 3 Spine2
  add(3, 4, 0, 15, 0);                                                          // 4 Neck
  add(4, 5, 0, 10, 0);                                                          // 5 Head
  add(3, 6, 5, 12, 0);                                                          // 6 LeftShoulder
  add(6, 7, 12, 0, 0);                                                          // 7 LeftArm
  add(7, 8, 28, 0, 0);                                                          // 8 LeftForeArm
  add(8, 9, 25, 0, 0);                                                          // 9 LeftHand
  add(3, 10, static_cast<std::uint8_t>(-17), 12, 0);                            // 10 RightArm
  add(10, 11, static_cast<std::uint8_t>(-28), 0, 0);                            // 11 RightForeArm
  add(11, 12, static_cast<std::uint8_t>(-25), 0, 0);                            // 12 RightHand
  add(0, 13, 9, static_cast<std::uint8_t>(-5), 0);                              // 13 LeftUpLeg
  add(13, 14, 0, static_cast<std::uint8_t>(-42), 0);                            // 14 LeftLeg
  add(14, 15, 0, static_cast<std::uint8_t>(-40), 0);                            // 15 LeftFoot
  add(15, 16, 0, static_cast<std::uint8_t>(-8), 12);                            // 16 LeftToeBase
  add(0, 17, static_cast<std::uint8_t>(-9), static_cast<std::uint8_t>(-5), 0);  // RightUpLeg
  add(17, 18, 0, static_cast<std::uint8_t>(-42), 0);                            // RightLeg
  add(18, 19, 0, static_cast<std::uint8_t>(-40), 0);                            // RightFoot
  seeds.push_back({"gen_mixamo.bin", mixamo});
  // The same rig with every name junk (topology alone).
  std::vector<std::uint8_t> junk = mixamo;
  junk[2] = 45;  // joint 0's name (then every joint's second byte)
  for (std::size_t at = 7; at < junk.size(); at += 5) junk[at] = 45;
  seeds.push_back({"gen_topology.bin", junk});
  // Names for all but the left shin (names and topology together).
  std::vector<std::uint8_t> mixed = mixamo;
  mixed[7 + 5 * 13] = 45;
  seeds.push_back({"gen_mixed.bin", mixed});
  seeds.push_back({"gen_chain.bin", {12, 20, 0, 0, 0, 10, 0, 0, 45, 0, 10, 0, 1, 45, 0, 10, 0}});
  return seeds;
}

}  // namespace
}  // namespace vistel

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  vistel::fuzz::writeSeedsIfAsked(*argc, *argv, vistel::makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using vistel::fuzz::check;
  const vistel::Skeleton s = vistel::skeletonFrom(std::span(data, size));
  const auto choice = vistel::inferJointMap(s);
  if (!choice.ok()) {
    check(!choice.error().message.empty(), "a refusal says why");
    return 0;
  }
  const vistel::JointMap& m = choice->map;
  check(m.canonical.size() == m.joint.size(), "one rig joint per canonical entry");
  check(choice->origin.size() == m.canonical.size(), "one origin per entry");
  std::set<std::string> canon, rig;
  for (std::size_t i = 0; i < m.canonical.size(); ++i) {
    check(vistel::canonicalIndex(m.canonical[i]) >= 0, "entries are canonical joints");
    check(canon.insert(m.canonical[i]).second, "each canonical joint mapped once");
    check(s.find(m.joint[i]) >= 0, "mapped joints exist in the skeleton");
    check(rig.insert(m.joint[i]).second, "each rig joint mapped once");
  }
  for (const std::string_view required : vistel::kDefaultRequiredJoints) {
    check(canon.count(std::string(required)) == 1, "every required joint is mapped");
  }
  return 0;
}
