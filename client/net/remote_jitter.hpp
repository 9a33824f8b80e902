// The jitter of what a viewer draws of each remote member against what that member sent
// (issue 21's remote smoothness, the "jerk" of --stats-json's playback figures): the jerk of
// the joint positions drawn at the playback times, and of those of every posture received,
// at their capture times, on the member's skeleton (MotionJerk, PlaybackStats::addDrawn and
// addSent). A ratio near 1 says the interpolation and extrapolation add no shake of their own.
//
// Split in two so the session lock is held only to copy: collect() under it, measure() after.
// Cost per member and frame: forward kinematics of the drawn posture and of each new one
// received (a few microseconds for 52 joints); no allocation once a member's buffers are sized.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "client/net/client_session.hpp"
#include "client/net/playback_stats.hpp"
#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"

namespace vistel::net {

class RemoteJitter {
 public:
  static constexpr int kMaxSentPerFrame = 64;  // newer postures copied per member and frame

  // Under the session lock, every frame: copies the postures remote member m received since
  // the last call.
  void collect(const RemoteMember& m);
  // After it: the drawn posture (at playback time t, server clock) and the collected ones on
  // the member's skeleton into stats (postures whose joint count differs are skipped).
  void measure(std::uint32_t id, const std::string& name, const Skeleton& skeleton, double t,
               const Posture& drawn, PlaybackStats& stats);
  // After the frame's collect() calls: forgets the members none was made for (they left).
  void endFrame();

 private:
  struct Track {
    double last_sent = -std::numeric_limits<double>::infinity();
    std::uint64_t frame = 0;  // the last frame collect() saw the member
    std::vector<Posture> sent;
    int count = 0;
    std::vector<glm::mat4> model;
    std::vector<glm::vec3> points;
  };
  void positions(const Skeleton& skeleton, const Posture& posture, Track& track);

  std::unordered_map<std::uint32_t, Track> tracks_;
  std::uint64_t frame_ = 1;
};

}  // namespace vistel::net
