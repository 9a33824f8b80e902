// Body roles: which joint of a skeleton plays each canonical humanoid role (hips, chest,
// l_forearm, ...), so the simulator, calibration and solver work on any skeleton — a
// mocap clip's or an avatar's — through its JointMap (common/motion/joint_map.hpp).
//
// The roles are the canonical joints of .team/RULES.md, in the same order; their names are
// the canonical names. Built once per skeleton (allocates); lookups are array reads.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/motion/joint_map.hpp"
#include "common/sensors/sensor_frame.hpp"

namespace vistel {

enum class Role : std::uint8_t {
  kHips,
  kSpine,
  kChest,
  kUpperChest,
  kNeck,
  kHead,
  kLClavicle,
  kLUpperarm,
  kLForearm,
  kLHand,
  kLThumb1,
  kLThumb2,
  kLThumb3,
  kLIndex1,
  kLIndex2,
  kLIndex3,
  kLMiddle1,
  kLMiddle2,
  kLMiddle3,
  kLRing1,
  kLRing2,
  kLRing3,
  kLPinky1,
  kLPinky2,
  kLPinky3,
  kRClavicle,
  kRUpperarm,
  kRForearm,
  kRHand,
  kRThumb1,
  kRThumb2,
  kRThumb3,
  kRIndex1,
  kRIndex2,
  kRIndex3,
  kRMiddle1,
  kRMiddle2,
  kRMiddle3,
  kRRing1,
  kRRing2,
  kRRing3,
  kRPinky1,
  kRPinky2,
  kRPinky3,
  kLThigh,
  kLShin,
  kLFoot,
  kLToes,
  kRThigh,
  kRShin,
  kRFoot,
  kRToes,
  kCount
};
inline constexpr int kRoleCount = static_cast<int>(Role::kCount);

// The canonical name of a role ("hips", "l_forearm", ...).
std::string_view roleName(Role role);

// Per-side roles: side 0 = left, 1 = right.
Role clavicleRole(int side);
Role upperarmRole(int side);
Role forearmRole(int side);
Role handRole(int side);
Role thighRole(int side);
Role shinRole(int side);
Role footRole(int side);
Role toesRole(int side);
// Finger f (0 thumb, 1 index, 2 middle, 3 ring, 4 pinky), segment k (0..2) of a side.
Role fingerRole(int side, int finger, int segment);

struct JointRoles {
  std::array<int, kRoleCount> joint;  // skeleton joint index per role, -1 when absent

  int operator[](Role role) const { return joint[static_cast<int>(role)]; }
  bool has(Role role) const { return joint[static_cast<int>(role)] >= 0; }
  // The segment a chest (sternum) sensor rides on: upper_chest, else chest, else spine.
  int chestSegment() const;
};

// Resolves every role through `map` (its canonical -> joint-name entries), or through the
// canonical names themselves when map is null (skeletons named like the default avatar).
// Requires hips, head, a chest segment and both arms (upperarm, forearm, hand), with each
// arm's joints and the head descending from the chest segment, and the chest from the hips;
// the error lists what is missing or misplaced.
Result<JointRoles> resolveJointRoles(const Skeleton& skeleton, const JointMap* map);

// True when `ancestor` is `joint` or one of its ancestors.
bool isAncestor(const Skeleton& skeleton, int ancestor, int joint);

// The participant's body axes at one posture, in model space: left (from the right to the
// left shoulder, horizontal), up (+Y) and forward (left x up). Model-space joint positions
// (njoint) in.
struct BodyFrame {
  glm::vec3 left{1.0f, 0.0f, 0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  glm::vec3 forward{0.0f, 0.0f, 1.0f};

  // Columns left, up, forward: body-frame coordinates -> model space.
  glm::mat3 matrix() const { return glm::mat3(left, up, forward); }
};
BodyFrame bodyFrameAt(const JointRoles& roles, std::span<const glm::vec3> positions);

}  // namespace vistel
