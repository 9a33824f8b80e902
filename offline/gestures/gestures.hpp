// vistel's own gesture clips: deterministic keyframed motions on a canonical-named skeleton,
// made by project code (no external data), for bots, demos and tests.
//
// Skeleton: the 52 canonical joints (joint_map.hpp) of an adult about 1.75 m tall,
// standing in a T-pose at rest (identity rest rotations, palms down, thumbs forward),
// metres, +Y up, facing +Z, its left side +X, soles on y = 0.
// Clips: 30 frames per second, several seconds each, looping exactly (the last frame
// equals the first), smooth (smoothstep slerp between keyframes; arms placed by two-bone
// inverse kinematics at the keys).
#pragma once

#include <string>
#include <vector>

#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/motion/bvh.hpp"

namespace vistel {

// Distance from a palm's centre on the hand bone's axis (halfway from the wrist to the
// middle knuckle) to the palm's skin, along the palm normal (the hand's local -Y).
inline constexpr float kGesturePalmHalfThickness = 0.013f;
inline constexpr double kGestureFrameTime = 1.0 / 30.0;

// The skeleton the bundled clips use (see above). Deterministic.
Skeleton makeGestureSkeleton();

// The bundled clips, in this order:
//   "wave"  - the right hand rises beside the head, palm forward, and the forearm waves;
//   "point" - the right arm points forward, then to the side (index finger out, head follows);
//   "clap"  - both hands meet in front of the chest three times, palm skin on palm skin;
//   "idle"  - breathing and a slow weight shift from foot to foot, feet planted.
// Each is a MotionClip in metres (unit_scale 1) on makeGestureSkeleton()'s hierarchy, its
// source the clip's name. Deterministic: equal on every call and machine.
std::vector<MotionClip> makeBundledGestures();

// Writes <out_dir>/<name>.bvh for every bundled clip (creating out_dir). The error names
// the file.
Status writeBundledGestures(const std::string& out_dir);

}  // namespace vistel
