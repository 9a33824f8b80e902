#include "common/anim/skinning_rig.hpp"

namespace vistel {

SkinningRig makeSkinningRig(const Skeleton& skeleton, const SkinMesh& mesh, SkinningMethod method,
                            int head_joint) {
  SkinningRig rig;
  rig.requested = method;
  rig.method = method;
  if (method == SkinningMethod::kSpineFfd) {
    rig.lattice = buildSpineLattice(skeleton, mesh, head_joint);
    if (rig.lattice.empty()) {
      rig.method = SkinningMethod::kDualQuaternion;
      rig.warning = "ffd skinning falls back to dqs: " + rig.lattice.warning;
    }
  } else if (method == SkinningMethod::kRigidSlerp) {
    rig.slerp = buildSlerpRig(skeleton, mesh);
  }
  return rig;
}

RigFrame makeRigFrame(const SkinningRig& rig) {
  RigFrame frame;
  if (rig.method == SkinningMethod::kRigidSlerp) frame.joints.resize(rig.slerp.parent.size());
  return frame;
}

void prepareRigFrame(const SkinningRig& rig, std::span<const glm::mat4> skin,
                     std::span<DualQuat> out_dq, RigFrame& out) {
  if (rig.method == SkinningMethod::kLinear) return;
  toDualQuats(skin, out_dq);
  if (rig.method == SkinningMethod::kSpineFfd) poseSpineLattice(rig.lattice, out_dq, out.lattice);
  if (rig.method == SkinningMethod::kRigidSlerp) poseSlerpRig(rig.slerp, out_dq, out.joints);
}

void skinRigRange(const SkinMesh& mesh, const SkinningRig& rig, std::span<const glm::mat4> skin,
                  std::span<const DualQuat> dq, const RigFrame& frame, std::size_t first,
                  std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals) {
  switch (rig.method) {
    case SkinningMethod::kLinear:
      skinLinear(mesh, skin, first, out_positions, out_normals);
      return;
    case SkinningMethod::kDualQuaternion:
      skinDualQuaternion(mesh, dq, first, out_positions, out_normals);
      return;
    case SkinningMethod::kSpineFfd:
      skinSpineLattice(mesh, rig.lattice, dq, frame.lattice, first, out_positions, out_normals);
      return;
    case SkinningMethod::kRigidSlerp:
      skinRigidSlerp(mesh, rig.slerp, dq, frame.joints, first, out_positions, out_normals);
      return;
  }
}

void skinMesh(const SkinMesh& mesh, const SkinningRig& rig, std::span<const glm::mat4> skin,
              std::span<DualQuat> scratch_dq, RigFrame& scratch, std::span<glm::vec3> out_positions,
              std::span<glm::vec3> out_normals) {
  prepareRigFrame(rig, skin, scratch_dq, scratch);
  skinRigRange(mesh, rig, skin, scratch_dq, scratch, 0, out_positions, out_normals);
}

}  // namespace vistel
