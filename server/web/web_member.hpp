// Visible spectators (vistel-server --web-members, web/PROTOCOL.md "Joining as a visible
// spectator"): what the page may send over its room WebSocket, and the member the web
// side makes of it. The web server joins the room as an ordinary member (a NetDriver to
// its own session server on loopback) with a camera-headed avatar made here, and sends
// the viewer's camera as that member's posture; the pure parts live here.
//
// Messages from the page (JSON text, at most 1 KiB, the socket's rate limit):
//   {"type":"join","name":TEXT?}  once: become a visible member (name optional)
//   {"type":"pose","x":X,"y":Y,"z":Z,"yaw":A,"pitch":B}  the camera in room space:
//       position in metres; yaw in radians about +Y, the view direction being
//       (sin yaw cos pitch, sin pitch, cos yaw cos pitch); pitch in radians, up positive.
//   {"type":"leave"}  stop being visible (the socket stays open)
// Anything else (not JSON, another type, a missing or non-finite number, a position
// farther than kMaxPoseDistanceM, a pitch beyond ±pi/2) is an error naming the problem.
//
// Pure; no allocation beyond the parsed message.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "common/anim/posture.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel::server {

inline constexpr double kMaxPoseDistanceM = 100.0;  // |x|, |y|, |z| of a pose
inline constexpr std::size_t kMaxSpectatorNameChars = 24;

struct SpectatorPose {
  double x = 0.0, y = 0.0, z = 0.0;  // room space, metres
  double yaw = 0.0;                  // radians about +Y (0: looking along +Z)
  double pitch = 0.0;                // radians, up positive, [-pi/2, pi/2]
};

struct SpectatorMessage {
  enum class Kind { kJoin, kPose, kLeave };
  Kind kind = Kind::kPose;
  std::string name;  // kJoin: as sent (not yet sanitised; may be empty)
  SpectatorPose pose;
};

// Parses one text message from the page; the error says what is wrong.
Result<SpectatorMessage> parseSpectatorMessage(std::string_view text);

// The member name of a visible spectator: the page's name with everything but ASCII
// letters, digits, '-', '_', '.' and inner spaces dropped, cut to kMaxSpectatorNameChars,
// then " (spectator)" appended; "spectator-N" (N = `serial`) when nothing is left.
std::string spectatorMemberName(std::string_view requested, std::uint64_t serial);

// The camera-headed avatar ("vistel-spectator"), built from boxes by code: joint 0
// "hips" (rest at (0, 1.0, 0)) and joint 1 "head" (0.6 m above it), facing +Z like every
// avatar; a grey body (torso and legs, bound to hips) and a camera for a head (a body, a
// lens toward +Z and a viewfinder, bound to head). Three materials, no textures, no
// implicit model (it takes no part in collisions). The same bytes on every call.
AvatarModel makeSpectatorAvatar();
// Its head joint's offset above the root (metres, model space +Y).
inline constexpr float kSpectatorHeadHeightM = 0.6f;

// The posture that puts the spectator avatar's head (the camera) at `pose` for a member
// standing at seat (seat_x, seat_z, seat_yaw) (room = T(x,0,z) R_y(yaw) model): root
// turned by yaw - seat_yaw about +Y, head pitched by `pose.pitch`, root translated so that
// the head joint lands on the pose's position. `time` is left 0 (the sender stamps it).
Posture spectatorPosture(const SpectatorPose& pose, float seat_x, float seat_z, float seat_yaw);

}  // namespace vistel::server
