#include "server/web/spectator_stream.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "common/wire/bit_stream.hpp"
#include "common/wire/posture_codec.hpp"
#include "vistel_version.hpp"

namespace vistel::server {
namespace {

template <typename T>
void put(std::vector<std::uint8_t>& out, T value) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // little-endian hosts (x86-64, aarch64)
  out.insert(out.end(), bytes, bytes + sizeof(T));
}

std::int16_t snorm16(float v) {
  if (!std::isfinite(v)) return 0;
  return static_cast<std::int16_t>(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f));
}

float finite(float v) { return std::isfinite(v) ? v : 0.0f; }

}  // namespace

void encodeSpectatorFrame(const SpectatorFrame& frame, std::vector<std::uint8_t>& out) {
  out.clear();
  const std::size_t members = std::min<std::size_t>(frame.postures.size(), 0xffff);
  const std::size_t props = std::min<std::size_t>(frame.props.size(), 0xffff);
  put<std::uint8_t>(out, kSpectatorFrameType);
  put<std::uint8_t>(out, kSpectatorFrameVersion);
  put<std::uint16_t>(out, static_cast<std::uint16_t>(members));
  put<std::uint16_t>(out, static_cast<std::uint16_t>(props));
  put<std::uint16_t>(out, 0);
  put<double>(out, frame.now);

  wire::PostureRecord record;
  Posture posture;
  for (std::size_t i = 0; i < members; ++i) {
    const SpectatorPosture& p = frame.postures[i];
    wire::ReadStream in(p.record);
    const bool ok = wire::serialize(in, record) && in.ok();
    if (ok) wire::decodePostureRecord(record, frame.now, posture);
    const std::size_t n = ok ? posture.rotations.size() : 0;
    put<std::uint32_t>(out, p.member);
    put<double>(out, ok ? posture.time : 0.0);
    put<std::uint16_t>(out, ok ? record.sequence : 0);
    put<std::uint8_t>(out, static_cast<std::uint8_t>(n));
    put<std::uint8_t>(out, 0);
    for (int c = 0; c < 3; ++c) put<float>(out, ok ? finite(posture.root_translation[c]) : 0.0f);
    for (std::size_t j = 0; j < n; ++j) {
      const glm::quat& q = posture.rotations[j];
      put<std::int16_t>(out, snorm16(q.x));
      put<std::int16_t>(out, snorm16(q.y));
      put<std::int16_t>(out, snorm16(q.z));
      put<std::int16_t>(out, snorm16(q.w));
    }
  }
  for (std::size_t i = 0; i < props; ++i) {
    const SpectatorProp& p = frame.props[i];
    put<std::uint32_t>(out, p.id);
    for (int c = 0; c < 3; ++c) put<float>(out, finite(p.position[c]));
    for (int c = 0; c < 3; ++c) put<float>(out, finite(p.velocity[c]));
    put<float>(out, finite(p.radius));
  }
}

std::string rosterJson(const LobbyRoomView& room, const SeatLayout& layout) {
  nlohmann::json members = nlohmann::json::array();
  for (const LobbyMemberView& m : room.members) {
    const SeatPlacement seat = seatPlacement(m.seat, layout);
    members.push_back(
        {{"id", m.id},
         {"name", m.name},
         {"avatar", m.avatar_ready ? nlohmann::json(m.avatar_hash) : nlohmann::json()},
         {"seat", {{"x", seat.x}, {"z", seat.z}, {"yaw", seat.yaw}}},
         {"joined_at", m.joined_at}});
  }
  return nlohmann::json{{"type", "roster"},
                        {"room", room.name},
                        {"created_at", room.created_at},
                        {"members", members}}
      .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string statusJson(std::string_view state, std::string_view message) {
  return nlohmann::json{{"type", "status"}, {"state", state}, {"message", message}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string helloJson(std::string_view room, double rate_hz) {
  return nlohmann::json{{"type", "hello"},
                        {"room", room},
                        {"rate_hz", rate_hz},
                        {"version", VISTEL_VERSION},
                        {"frame_version", kSpectatorFrameVersion}}
      .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace vistel::server
