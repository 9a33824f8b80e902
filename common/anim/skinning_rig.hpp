// SkinningRig: what one mesh needs to be skinned by any of the four methods of the rigid
// component (DESIGN.md §4: LBS, DQS, the spine lattice, rigid + slerp), built once at load,
// and the per-frame calls that run it. Shared by vistel-avatar pose/deform, DeformScene and
// the client's RoomView.
//
// Per frame, one thread: prepareRigFrame (joints' dual quaternions, the lattice's pose or
// the joints' relative motions; O(njoint)) into a RigFrame sized once by makeRigFrame;
// then any thread, any vertex range: skinRigRange. Neither allocates.
#pragma once

#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/ffd_skinning.hpp"
#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/anim/skinning.hpp"
#include "common/anim/slerp_skinning.hpp"

namespace vistel {

struct SkinningRig {
  SkinningMethod requested = SkinningMethod::kDualQuaternion;
  SkinningMethod method = SkinningMethod::kDualQuaternion;  // what runs: the requested one,
                                                            // or kDualQuaternion when
                                                            // kSpineFfd found no spine
  SpineLattice lattice;                                     // kSpineFfd
  SlerpRig slerp;                                           // kRigidSlerp
  std::string warning;  // why method differs from requested, else empty
};

// Builds the rig of a validated skeleton and skin (validateSkeleton, validateSkinMesh).
// head_joint: for kSpineFfd, the head joint when the caller knows it (a joint map's
// canonical "head"), -1 = found by name (see buildSpineLattice). Never fails: a skeleton
// without a spine chain gets kDualQuaternion and a warning. Allocates; O(nvert).
SkinningRig makeSkinningRig(const Skeleton& skeleton, const SkinMesh& mesh, SkinningMethod method,
                            int head_joint = -1);

// What a rig needs per frame beyond the joints' dual quaternions.
struct RigFrame {
  SpineLatticePose lattice;        // kSpineFfd: the lattice posed
  std::vector<SlerpJoint> joints;  // kRigidSlerp: each joint relative to its parent (njoint)
};
// A frame sized for the rig (allocates).
RigFrame makeRigFrame(const SkinningRig& rig);

// This frame's per-joint data: out_dq (njoint) the rigid parts of `skin` (bind -> posed,
// njoint) for every method but LBS; out the rest (out from makeRigFrame(rig)).
void prepareRigFrame(const SkinningRig& rig, std::span<const glm::mat4> skin,
                     std::span<DualQuat> out_dq, RigFrame& out);

// Posed positions and normals (same space as `skin`) of vertices [first, first +
// out.size()) by the rig's method, from what prepareRigFrame wrote. kLinear and
// kDualQuaternion give exactly skinLinear and skinDualQuaternion.
void skinRigRange(const SkinMesh& mesh, const SkinningRig& rig, std::span<const glm::mat4> skin,
                  std::span<const DualQuat> dq, const RigFrame& frame, std::size_t first,
                  std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals);

// Convenience: the whole mesh in one call (scratch_dq: njoint entries; scratch from
// makeRigFrame(rig)). Allocates nothing.
void skinMesh(const SkinMesh& mesh, const SkinningRig& rig, std::span<const glm::mat4> skin,
              std::span<DualQuat> scratch_dq, RigFrame& scratch, std::span<glm::vec3> out_positions,
              std::span<glm::vec3> out_normals);

}  // namespace vistel
