// A motion clip played on a participant's avatar: what bots stream, and the site
// client's --source bvh:FILE. Postures on the wire are always in the sender's avatar
// skeleton, so a clip is mapped onto it: directly when every avatar joint is a clip
// joint of the same name, parent, rest rotation and rest bone direction (local
// rotations then mean the same on both), otherwise retargeted through the joint maps
// of config/skeletons (Retargeter, which corrects for differing rest poses).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/retarget.hpp"

namespace vistel::net {

class ClipPlayer {
 public:
  // Fails (naming the clip) when the avatar has neither the clip's joints nor a joint
  // map that lets the clip be retargeted onto it.
  static Result<std::unique_ptr<ClipPlayer>> create(MotionClip clip, const Skeleton& avatar,
                                                    const std::string& config_dir = "config");

  double frameTime() const { return clip_.frame_time; }
  double duration() const { return clip_.duration(); }
  bool retargeted() const { return retargeter_.has_value(); }
  const std::string& source() const { return clip_.source; }

  // The avatar's posture at clip time t seconds (wrapped into the clip when loop, else
  // clamped); out is sized once and reused. Not thread-safe (scratch state).
  void sample(double t, bool loop, Posture& out);

 private:
  ClipPlayer() = default;

  MotionClip clip_;
  std::unique_ptr<Skeleton> clip_skeleton_;  // stable address (the retargeter points here)
  std::unique_ptr<Skeleton> avatar_skeleton_;
  std::vector<int> clip_joint_of_avatar_;  // direct mapping (navatar), or empty
  std::optional<Retargeter> retargeter_;
  Posture clip_posture_;  // scratch
};

}  // namespace vistel::net
