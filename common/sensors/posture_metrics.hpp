// Scoring solved postures against the true ones on the same skeleton (the simulator's clip):
// MPJPE (mean per-joint position error) over the upper body and over all joints, MPJRE
// (mean per-joint rotation error, model-space rotations), and jitter as the mean jerk
// (third difference of joint positions) of the solved and of the true motion; pops as the
// largest frame-to-frame jump of any joint; lag by cross-correlating joint velocities.
#pragma once

#include <span>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/sensors/body_roles.hpp"

namespace vistel {

struct PostureMetrics {
  int frames = 0;
  double mpjpe_upper_m = 0.0;  // spine joints, neck, head, shoulders, elbows, wrists
  double mpjpe_all_m = 0.0;    // every joint of the skeleton
  double mpjpe_legs_m = 0.0;   // thighs (hips), shins (knees), feet (ankles), toes
  double mpjre_upper_deg = 0.0;
  double mpjre_all_deg = 0.0;
  double max_upper_m = 0.0;  // worst single upper-body joint error
  double jerk_solved = 0.0;  // mean |jerk| over all joints, m/s^3
  double jerk_truth = 0.0;
  double jerk_upper_solved = 0.0;  // ... over the upper-body joints only
  double jerk_upper_truth = 0.0;
  double max_jump_solved_m = 0.0;  // largest frame-to-frame move of any joint (pops)
  double max_jump_truth_m = 0.0;
  // How far the solved upper body trails the truth, seconds (negative: it leads): the shift
  // that maximises the normalised cross-correlation of the upper-body joints' frame-to-frame
  // velocities, searched within +-0.25 s and refined to a fraction of a frame by a parabola.
  double lag_s = 0.0;

  double jitterRatio() const { return jerk_truth > 0.0 ? jerk_solved / jerk_truth : 0.0; }
  double jumpRatio() const {
    return max_jump_truth_m > 0.0 ? max_jump_solved_m / max_jump_truth_m : 0.0;
  }
};

// The leg joints by role: thighs, shins, feet, toes — those the skeleton has.
std::vector<int> legJoints(const JointRoles& roles);

// The upper-body joints by role: spine, chest, upper_chest, neck, head, upper arms (the
// shoulder joints), forearms (elbows), hands (wrists) — those the skeleton has.
std::vector<int> upperBodyJoints(const JointRoles& roles);

// truth.size() == solved.size() postures on `skeleton`, one every frame_time seconds (only
// the common prefix is scored). Allocates (poses every frame); cost O(frames x joints).
PostureMetrics measurePostures(const Skeleton& skeleton, const JointRoles& roles,
                               std::span<const Posture> truth, std::span<const Posture> solved,
                               double frame_time);

}  // namespace vistel
