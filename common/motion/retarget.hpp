// Retargeting postures from one skeleton (a mocap clip's) onto another (an avatar's)
// through the canonical joints of their JointMaps, with rest-pose correction: the two
// rest poses may differ (T-pose clip, A-pose avatar), so each mapped joint's world
// rotation change relative to an aligned reference is transferred, not local angles.
//
// How: create() builds an aligned reference of the target, whose mapped bones point the
// way the source's bones point in the source reference (its rest pose, or a given natural
// pose), parents first: the hips and the spine get a whole frame (up towards the neck,
// left-right from the thighs or the shoulders), chest and upper chest only the twist about
// their bone towards the neck (each spine keeps its own curvature), other mapped joints
// swing their bone (towards the next mapped joint down the chain: upper arm -> forearm)
// onto the source's; a half turn goes through the body's side. Per posture, mapped target joint j
// gets the world rotation
//   W_t(j) = B * W_s(s) * W_s,ref(s)^-1 * A_t(j)   (s = its source joint, A_t aligned ref)
// where B is the swing that carries the bone's direction as predicted by W_s(s) onto the
// source's actual direction to the next mapped joint (identity unless unmapped source joints
// bend in between, such as the CMU clips' lower neck), so every mapped limb bone of the
// target points the way the source's does. Spines divided differently (3 joints or 4,
// short or long segments) bend alike: each target spine joint follows the chord of the
// source's spine polyline between its own bone's arc fractions. Unmapped target joints keep their
// local rest rotation, and world rotations become local ones. The target hips follow the source
// hips: horizontally by their displacement from the reference, vertically by their height above the
// floor, both scaled by the ratio of hip heights (hips-to-ankle leg length along the body's up
// axis).
#pragma once

#include <optional>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"

namespace vistel {

struct RetargetOptions {
  // A natural standing pose of the source (T-pose, A-pose or arms down, anatomical joint
  // twists) to align against, in place of its rest pose. Same joint count as the source.
  // Needed when the rest pose is not one (the gesture clips' zero pose); forClip picks it.
  std::optional<Posture> source_reference;
  // Model-space height (y, metres) of the floor under the source; BVH clips stand on y = 0.
  float source_floor = 0.0f;
  // Height above source_floor of the ankles (canonical feet) of a foot planted on the
  // floor. Default: the target's, scaled (forClip: the clip's lowest ankle over all frames).
  std::optional<float> source_ankle_height;
  // The floor under the target; default: the lowest joint of the target's rest pose (an
  // avatar stands on its floor at rest, its ankles at rest height above it).
  std::optional<float> target_floor;
};

class Retargeter {
 public:
  // Fails when a skeleton is malformed, when a map or a skeleton lacks one of the
  // kDefaultRequiredJoints (hips, spine, head, upper/lower arms and legs; the message names
  // map, canonical joint and joint), when the target map maps a joint above the target
  // hips, or when source_reference does not fit the source. Joints a map names but a
  // skeleton lacks, and canonical joints only one map names, are left unmapped. Copies what
  // it needs: the skeletons and maps need not outlive the Retargeter. Cost: O(n * depth).
  static Result<Retargeter> create(const Skeleton& source, const JointMap& source_map,
                                   const Skeleton& target, const JointMap& target_map,
                                   const RetargetOptions& options = {});

  // create() for a clip's skeleton (clipSkeleton(clip)), with clipReferencePosture() as
  // the source reference and the clip's lowest ankle (over all frames) as its planted
  // ankle height, unless options give them. Postures from samplePosture(clip, ...) are then
  // valid input to apply(). Cost: one pass of forward kinematics over the clip.
  static Result<Retargeter> forClip(const MotionClip& clip, const JointMap& clip_map,
                                    const Skeleton& target, const JointMap& target_map,
                                    RetargetOptions options = {});

  // Target posture (rotations resized once; translations left empty) for a source posture
  // on the source skeleton (njoint rotations; translations empty or njoint). Allocates
  // nothing after the first call with a given `out`. Not thread-safe (one Retargeter per
  // thread): it reuses scratch buffers sized in create().
  void apply(const Posture& source, Posture& out) const;

  int sourceJointCount() const { return static_cast<int>(source_.names.size()); }
  int targetJointCount() const { return static_cast<int>(target_parents_.size()); }
  // The source joint driving target joint j, or -1 when j keeps its rest rotation.
  int sourceOf(int target_joint) const {
    return source_of_target_[static_cast<std::size_t>(target_joint)];
  }
  // Target metres per source metre of hips motion.
  float translationScale() const { return translation_scale_; }

 private:
  Retargeter() = default;

  Skeleton source_;                              // copy, for forward kinematics
  std::vector<int> target_parents_;              // (ntarget)
  std::vector<glm::quat> target_rest_rotation_;  // (ntarget) local rest rotation
  std::vector<int> source_of_target_;            // (ntarget) mapped source joint or -1
  std::vector<glm::quat> offset_;                // (ntarget) W_s,ref(s)^-1 * A_t(j), mapped j
  std::vector<int> direction_source_;            // (ntarget) source joint j's bone points to, or -1
  std::vector<glm::vec3> direction_rest_;        // (ntarget) that bone's unit direction in the
                                                 // source joint's frame at the reference
  std::vector<glm::vec2> chord_;                 // (ntarget) torso joints: arc fractions (from,
                                                 // to) of their chord on the source's spine
  std::vector<int> torso_source_;                // source spine polyline: joints, spine to neck
  std::vector<float> torso_fraction_;            // their arc fractions at the reference
  int source_hips_ = 0;
  int target_hips_ = 0;
  glm::vec3 source_reference_hips_{0.0f};  // source hips in the reference pose (metres)
  glm::vec3 target_rest_hips_{0.0f};       // target hips at rest (metres)
  glm::vec3 root_to_hips_{0.0f};           // target hips minus root at rest (model space)
  float source_ground_ = 0.0f;             // source y of a planted ankle
  float target_ground_ = 0.0f;             // target y of a planted ankle
  float translation_scale_ = 1.0f;
  mutable std::vector<glm::mat4> scratch_source_model_;  // (nsource)
  mutable std::vector<glm::quat> scratch_source_world_;  // (nsource)
  mutable std::vector<glm::quat> scratch_target_world_;  // (ntarget)
};

// The pose to align a clip against: its zero pose when that is a natural standing pose
// (torso within 30 degrees of +Y, both legs within 45 degrees of -Y), else frame 0 (the
// gesture clips' zero pose lays every bone along +-X and twists a leg half a turn). Joints
// the map lacks make the zero pose count as natural. out is resized.
void clipReferencePosture(const MotionClip& clip, const JointMap& clip_map, Posture& out);

}  // namespace vistel
