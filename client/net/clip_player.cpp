#include "client/net/clip_player.hpp"

#include <cmath>

#include "common/math/transform.hpp"
#include "common/motion/auto_joint_map.hpp"
#include "common/motion/joint_map.hpp"

namespace vistel::net {

Result<std::unique_ptr<ClipPlayer>> ClipPlayer::create(MotionClip clip, const Skeleton& avatar,
                                                       const std::string& config_dir) {
  if (clip.frame_count < 1 || !(clip.frame_time > 0.0)) {
    return fail("{}: the clip has no frames", clip.source);
  }
  std::unique_ptr<ClipPlayer> p(new ClipPlayer());
  p->clip_skeleton_ = std::make_unique<Skeleton>(clipSkeleton(clip));
  p->avatar_skeleton_ = std::make_unique<Skeleton>(avatar);
  p->clip_ = std::move(clip);
  const Skeleton& cs = *p->clip_skeleton_;
  const Skeleton& as = *p->avatar_skeleton_;

  // Direct: every avatar joint is a clip joint of the same name, parent, rest rotation
  // and rest bone direction (then local rotations mean the same on both; proportions
  // may differ).
  std::vector<int> map(static_cast<std::size_t>(as.jointCount()), -1);
  bool direct = true;
  for (int j = 0; j < as.jointCount() && direct; ++j) {
    const auto ju = static_cast<std::size_t>(j);
    const int c = cs.find(as.names[ju]);
    map[ju] = c;
    if (c < 0) {
      direct = false;
      break;
    }
    const auto cu = static_cast<std::size_t>(c);
    const int ap = as.parents[ju];
    const int cp = cs.parents[cu];
    const bool same_parent =
        (ap == kNoParent && cp == kNoParent) ||
        (ap != kNoParent && cp != kNoParent &&
         as.names[static_cast<std::size_t>(ap)] == cs.names[static_cast<std::size_t>(cp)]);
    const bool same_rotation =
        angleBetween(cs.rest_local[cu].rotation, as.rest_local[ju].rotation) < 1e-3f;
    bool same_direction = true;
    if (ap != kNoParent) {
      const glm::vec3 a = as.rest_local[ju].translation;
      const glm::vec3 b = cs.rest_local[cu].translation;
      const float la = glm::length(a);
      const float lb = glm::length(b);
      same_direction = (la < 1e-6f && lb < 1e-6f) ||
                       (la >= 1e-6f && lb >= 1e-6f && glm::dot(a / la, b / lb) > 0.9986f);  // 3 deg
    }
    direct = same_parent && same_rotation && same_direction;
  }
  if (direct) {
    p->clip_joint_of_avatar_ = std::move(map);
    return p;
  }

  // Otherwise retarget through the joint maps.
  auto maps = loadJointMaps(config_dir);
  if (!maps) return withContext(p->clip_.source, maps.error());
  auto source_map = chooseJointMap(*maps, cs);  // a config map, else one inferred
  if (!source_map) return withContext(p->clip_.source + " (clip skeleton)", source_map.error());
  auto target_map = chooseJointMap(*maps, as);
  if (!target_map) return withContext(p->clip_.source + " (avatar skeleton)", target_map.error());
  // forClip: against the clip's natural pose (its zero pose may not be one: the gesture
  // clips' lays the bones along the axes and twists a leg half a turn).
  auto retargeter = Retargeter::forClip(p->clip_, source_map->map, as, target_map->map);
  if (!retargeter) return withContext(p->clip_.source, retargeter.error());
  p->retargeter_.emplace(std::move(*retargeter));
  return p;
}

void ClipPlayer::sample(double t, bool loop, Posture& out) {
  // Clip time.
  const double d = clip_.duration();
  if (loop && d > 0.0) {
    t = std::fmod(t, d);
    if (t < 0.0) t += d;
  }
  samplePostureAt(clip_, t, clip_posture_);

  // Onto the avatar.
  if (retargeter_) {
    retargeter_->apply(clip_posture_, out);
  } else {
    const std::size_t n = clip_joint_of_avatar_.size();
    out.rotations.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      out.rotations[j] =
          clip_posture_.rotations[static_cast<std::size_t>(clip_joint_of_avatar_[j])];
    }
    out.root_translation = clip_posture_.root_translation;
  }
  out.translations.clear();
  out.time = t;
}

}  // namespace vistel::net
