// Rigid + slerp skinning (DESIGN.md §4: "limb vertices follow their bone rigidly and
// joint-region vertices interpolate the two bones' rotations"), the paper's third rigid
// scheme beside LBS and DQS.
//
// Each vertex moves rigidly with its dominant bone a (the first slot of largest weight);
// every other bone i then bends it, in a's bind frame, by the share w_i of each joint on
// the skeleton path from a to i: joint j (rest origin o_j, rotation L_j and translation
// tau_j relative to its parent, both from the skinning transforms) moves the vertex by
//   p <- o_j + L_j^(w_i) (p - o_j) + w_i tau_j
// (L^w the slerp from the identity, the shorter arc; tau_j = 0 while joints stay
// connected), deepest joint first, and by the inverse share on the part of the path that
// climbs from a towards i's branch. With two bones (joint connected) this is exactly the
// rotation slerp(R_a, R_b, w_b) about their joint with the translation blended linearly,
//   p' = slerp(R_a, R_b, w_b) (p - o) + w_a T_a(o) + w_b T_b(o),
// so a vertex on one bone moves rigidly with it, a twist keeps the radius about the bone
// (no candy-wrapper collapse, unlike LBS) and a bend rounds the joint like DQS. Bones
// further apart (chest and upper arm through the clavicle, pelvis and thigh on a groin
// vertex that also follows the spine) turn the vertex about the joints actually between
// them, each by its share. Turning about joints rather than the model origin is the idea of
// spherical blend skinning (Kavan & Zara 2005); here the centres are the skeleton's joints,
// found at load, rather than solved per frame. Normals turn by the composed rotation.
// Model space, metres.
//
// Cost: the rig once per mesh (buildSlerpRig: O(nvert * k * depth), allocates); per frame
// poseSlerpRig (O(njoint)) then O(k * path length) slerps per vertex (path length 1
// between a parent and a child), no allocation, any sub-range on any thread.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/math/dual_quat.hpp"

namespace vistel {

struct SlerpRig {
  std::vector<int> parent;             // parent joint (njoint), kNoParent for the root
  std::vector<glm::vec3> origin;       // rest joint origin (njoint), model space
  std::vector<std::uint8_t> dominant;  // slot of the dominant bone per vertex (nvert)
  // Per influence slot (nvert * k, as SkinMesh::weights) the path from the dominant bone to
  // that slot's bone: steps path[path_begin[s] .. path_begin[s + 1]), in the order applied.
  // A step j >= 0 applies joint j's share; ~j (negative) its inverse share.
  std::vector<std::uint32_t> path_begin;  // (nvert * k + 1)
  std::vector<std::int32_t> path;
};

// Builds the rig of a validated skeleton and skin.
SlerpRig buildSlerpRig(const Skeleton& skeleton, const SkinMesh& mesh);

// One joint's motion relative to its parent this frame, in bind space: L_j and tau_j.
struct SlerpJoint {
  glm::quat local{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 tau{0.0f};
};

// This frame's SlerpJoint of every joint (out: njoint; the root's is unused) from the
// joints' unit dual quaternions (bind -> posed, see toDualQuats). Allocates nothing.
void poseSlerpRig(const SlerpRig& rig, std::span<const DualQuat> skin, std::span<SlerpJoint> out);

// Posed positions and normals (model space) for vertices [first, first + out.size()).
// skin: one unit dual quaternion per joint; joints: this frame's poseSlerpRig. Allocates
// nothing.
void skinRigidSlerp(const SkinMesh& mesh, const SlerpRig& rig, std::span<const DualQuat> skin,
                    std::span<const SlerpJoint> joints, std::size_t first,
                    std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals);

}  // namespace vistel
