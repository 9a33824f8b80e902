// What a spectator's WebSocket carries (web/PROTOCOL.md): JSON text messages for the
// roster and the room's state, and a compact binary frame of every member's newest
// posture and the props, sent at the room's rate.
//
// Binary frame (little-endian, version 1):
//   u8 type = 1 | u8 version = 1 | u16 member count | u16 prop count | u16 0
//   | f64 server time (s, the server clock of capture times)
//   per member:  u32 id | f64 capture time (s) | u16 sequence | u8 joint count n (0: no
//                posture yet) | u8 0 | f32 root translation x, y, z (model space, m)
//                | n x i16 quaternion x, y, z, w (local joint rotations, / 32767)
//   per prop:    u32 id | f32 position x, y, z (room space, m) | f32 velocity x, y, z
//                (m/s) | f32 radius (m)
// A member's joints are in its avatar's skeleton order (the .glb's skin joints).
//
// Pure; cost O(members x joints). Bad posture bytes (never produced by a room) give a
// member with no posture.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/scene/seat_layout.hpp"
#include "server/shell/server_shell.hpp"

namespace vistel::server {

inline constexpr std::uint8_t kSpectatorFrameType = 1;
inline constexpr std::uint8_t kSpectatorFrameVersion = 1;
inline constexpr std::size_t kSpectatorFrameHeaderBytes = 16;
inline constexpr std::size_t kSpectatorMemberHeaderBytes = 28;
inline constexpr std::size_t kSpectatorPropBytes = 32;

// The binary frame of a sample (appended to out, which is cleared first).
void encodeSpectatorFrame(const SpectatorFrame& frame, std::vector<std::uint8_t>& out);

// {"type":"roster","room":..,"created_at":..,"members":[{"id","name","avatar" (hash, or
// null until the server has the file),"seat":{"x","z","yaw"},"joined_at"}]}: the room's
// members and where they stand (the seat transform places an avatar's model space).
std::string rosterJson(const LobbyRoomView& room, const SeatLayout& layout);

// {"type":"status","state":STATE,"message":TEXT}; states: "live" (the room is open),
// "absent" (no such room open), "closed" (it was open on this stream and closed: everyone
// left), "stopping" (the server shuts down), "unauthorized".
std::string statusJson(std::string_view state, std::string_view message);

// {"type":"hello","room":..,"rate_hz":..,"version":..}: the first message.
std::string helloJson(std::string_view room, double rate_hz);

}  // namespace vistel::server
