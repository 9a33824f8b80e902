// The rigid component: skinning kernels over spans (DESIGN.md §4). Linear blend
// skinning and dual-quaternion skinning (Kavan et al. 2007). They allocate nothing and
// own nothing; callers size the outputs once from the mesh. The two methods that need
// per-mesh data built at load (the spine lattice, the slerp rig's joint paths) live in
// ffd_skinning.hpp and slerp_skinning.hpp; skinning_rig.hpp runs any of the four.
#pragma once

#include <optional>
#include <span>
#include <string_view>

#include <glm/glm.hpp>

#include "common/anim/skin_mesh.hpp"
#include "common/math/dual_quat.hpp"

namespace vistel {

enum class SkinningMethod {
  kLinear,          // "lbs": linear blend of the bone matrices
  kDualQuaternion,  // "dqs": dual quaternions (Kavan et al. 2007), the default
  kSpineFfd,        // "ffd": the torso swept along a lattice on the spine, the rest as DQS
                    // (ffd_skinning.hpp)
  kRigidSlerp,      // "slerp": rigid limbs, slerp of the bone rotations at the joints
                    // (slerp_skinning.hpp)
};

// "lbs", "dqs", "ffd", "slerp".
std::string_view skinningMethodName(SkinningMethod method);
// The method of one of those names, or nullopt.
std::optional<SkinningMethod> parseSkinningMethod(std::string_view name);

// Posed positions and normals (model space) for vertices [first, first + out.size()).
// skin: one matrix per joint (bind model space -> posed model space), see
// skinningMatrices(). Normals are the rest normals carried by each vertex's blended
// transform (renormalised), not recomputed from the posed mesh.
void skinLinear(const SkinMesh& mesh, std::span<const glm::mat4> skin, std::size_t first,
                std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals);

// As skinLinear, blending one unit dual quaternion per joint (see toDualQuats()).
void skinDualQuaternion(const SkinMesh& mesh, std::span<const DualQuat> skin, std::size_t first,
                        std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals);

// Rigid parts of the skinning matrices as dual quaternions (njoint).
void toDualQuats(std::span<const glm::mat4> skin, std::span<DualQuat> out);

// Convenience: pose the whole mesh with LBS or DQS. scratch_dq must hold njoint entries
// when method is kDualQuaternion. kSpineFfd and kRigidSlerp need data built at load (see
// skinning_rig.hpp); given here they skin as kDualQuaternion.
void skinMesh(const SkinMesh& mesh, SkinningMethod method, std::span<const glm::mat4> skin,
              std::span<DualQuat> scratch_dq, std::span<glm::vec3> out_positions,
              std::span<glm::vec3> out_normals);

}  // namespace vistel
