#include "common/sensors/body_roles.hpp"

#include <string>

namespace vistel {
namespace {

constexpr std::array<std::string_view, kRoleCount> kRoleNames = {
    "hips",       "spine",     "chest",     "upper_chest", "neck",       "head",       "l_clavicle",
    "l_upperarm", "l_forearm", "l_hand",    "l_thumb1",    "l_thumb2",   "l_thumb3",   "l_index1",
    "l_index2",   "l_index3",  "l_middle1", "l_middle2",   "l_middle3",  "l_ring1",    "l_ring2",
    "l_ring3",    "l_pinky1",  "l_pinky2",  "l_pinky3",    "r_clavicle", "r_upperarm", "r_forearm",
    "r_hand",     "r_thumb1",  "r_thumb2",  "r_thumb3",    "r_index1",   "r_index2",   "r_index3",
    "r_middle1",  "r_middle2", "r_middle3", "r_ring1",     "r_ring2",    "r_ring3",    "r_pinky1",
    "r_pinky2",   "r_pinky3",  "l_thigh",   "l_shin",      "l_foot",     "l_toes",     "r_thigh",
    "r_shin",     "r_foot",    "r_toes"};

constexpr int kArmStride = static_cast<int>(Role::kRClavicle) - static_cast<int>(Role::kLClavicle);
constexpr int kLegStride = static_cast<int>(Role::kRThigh) - static_cast<int>(Role::kLThigh);

Role armRole(Role left, int side) {
  return static_cast<Role>(static_cast<int>(left) + side * kArmStride);
}
Role legRole(Role left, int side) {
  return static_cast<Role>(static_cast<int>(left) + side * kLegStride);
}

}  // namespace

std::string_view roleName(Role role) { return kRoleNames[static_cast<int>(role)]; }

Role clavicleRole(int side) { return armRole(Role::kLClavicle, side); }
Role upperarmRole(int side) { return armRole(Role::kLUpperarm, side); }
Role forearmRole(int side) { return armRole(Role::kLForearm, side); }
Role handRole(int side) { return armRole(Role::kLHand, side); }
Role thighRole(int side) { return legRole(Role::kLThigh, side); }
Role shinRole(int side) { return legRole(Role::kLShin, side); }
Role footRole(int side) { return legRole(Role::kLFoot, side); }
Role toesRole(int side) { return legRole(Role::kLToes, side); }
Role fingerRole(int side, int finger, int segment) {
  return armRole(static_cast<Role>(static_cast<int>(Role::kLThumb1) + 3 * finger + segment), side);
}

int JointRoles::chestSegment() const {
  if (has(Role::kUpperChest)) return (*this)[Role::kUpperChest];
  if (has(Role::kChest)) return (*this)[Role::kChest];
  return (*this)[Role::kSpine];
}

bool isAncestor(const Skeleton& skeleton, int ancestor, int joint) {
  while (joint >= 0) {
    if (joint == ancestor) return true;
    joint = skeleton.parents[static_cast<std::size_t>(joint)];
  }
  return false;
}

Result<JointRoles> resolveJointRoles(const Skeleton& skeleton, const JointMap* map) {
  JointRoles roles;
  roles.joint.fill(-1);
  for (int r = 0; r < kRoleCount; ++r) {
    std::string_view name = kRoleNames[r];
    if (map != nullptr) {
      name = {};
      for (std::size_t i = 0; i < map->canonical.size() && i < map->joint.size(); ++i) {
        if (map->canonical[i] == kRoleNames[r]) {
          name = map->joint[i];
          break;
        }
      }
      if (name.empty()) continue;
    }
    roles.joint[r] = skeleton.find(name);
  }
  // Required roles, and the tree shape the solver relies on.
  std::string missing;
  const Role required[] = {Role::kHips,  Role::kHead,      Role::kLUpperarm, Role::kLForearm,
                           Role::kLHand, Role::kRUpperarm, Role::kRForearm,  Role::kRHand};
  for (Role r : required) {
    if (!roles.has(r)) missing += fmt::format(" {}", roleName(r));
  }
  if (roles.chestSegment() < 0) missing += " chest (or upper_chest or spine)";
  const std::string source = map != nullptr ? fmt::format("joint map '{}'", map->name)
                                            : std::string("canonical joint names");
  if (!missing.empty()) {
    return fail("skeleton lacks required joints through {}:{}", source, missing);
  }
  const int chest = roles.chestSegment();
  auto require = [&](int ancestor, int joint, std::string_view what) -> Status {
    if (!isAncestor(skeleton, ancestor, joint)) {
      return fail("skeleton joints through {}: {} ('{}' is not an ancestor of '{}')", source, what,
                  skeleton.names[static_cast<std::size_t>(ancestor)],
                  skeleton.names[static_cast<std::size_t>(joint)]);
    }
    return {};
  };
  Status s = require(roles[Role::kHips], chest, "the chest must descend from the hips");
  if (s.ok()) s = require(chest, roles[Role::kHead], "the head must descend from the chest");
  for (int side = 0; side < 2 && s.ok(); ++side) {
    s = require(chest, roles[upperarmRole(side)], "the arms must descend from the chest");
    if (s.ok()) s = require(roles[upperarmRole(side)], roles[forearmRole(side)], "arm order");
    if (s.ok()) s = require(roles[forearmRole(side)], roles[handRole(side)], "arm order");
    if (s.ok() && roles[upperarmRole(side)] == roles[forearmRole(side)]) {
      s = fail("upper arm and forearm are the same joint");
    }
  }
  if (!s.ok()) return s.error();
  return roles;
}

BodyFrame bodyFrameAt(const JointRoles& roles, std::span<const glm::vec3> positions) {
  BodyFrame f;
  glm::vec3 across = positions[static_cast<std::size_t>(roles[Role::kLUpperarm])] -
                     positions[static_cast<std::size_t>(roles[Role::kRUpperarm])];
  across.y = 0.0f;
  if (glm::dot(across, across) < 1e-8f) across = glm::vec3(1.0f, 0.0f, 0.0f);
  f.left = glm::normalize(across);
  f.up = glm::vec3(0.0f, 1.0f, 0.0f);
  f.forward = glm::cross(f.left, f.up);
  return f;
}

}  // namespace vistel
