// The lobby's side of shared dents (proto/SESSION.md §2.5): a member's Dents for its own
// avatar or a prop of its room is checked, kept as that body's newest and relayed to the
// rest of the room; a joiner gets what the room keeps. What is ignored is counted and
// logged under a reason ("dents not shared", "dents for another body", "malformed dents",
// "dents too often", "dents over the byte rate") and the sender stays: a client with a bug
// in its dents still meets.
#include <algorithm>
#include <cmath>
#include <span>
#include <string>

#include <fmt/format.h>

#include "common/scene/dent_record.hpp"
#include "server/core/lobby.hpp"

namespace vistel::server {
namespace {

std::span<const std::uint32_t> repeatedSpan(
    const google::protobuf::RepeatedField<std::uint32_t>& f) {
  return {f.data(), static_cast<std::size_t>(f.size())};
}

}  // namespace

void Lobby::handleDents(Connection& c, const control::Dents& dents, double now, Effects& fx) {
  Member* m = findMember(c.member.value);
  if (m == nullptr) return;
  RoomRecord& room = rooms_.at(m->room.value);
  const auto ignore = [&](std::string_view reason, const std::string& why) {
    drops_.drop(now, reason,
                fmt::format("{} {:#x} from member {:#x}: {}", dents.prop() ? "prop" : "avatar",
                            dents.body_id(), m->id.value, why));
  };
  if (config_.max_dent_vertices == 0) {
    ignore("dents not shared", "[limits] max_dent_vertices is 0");
    return;
  }
  // Whose: a member sends its own avatar's dents, and any prop's of its room.
  const auto prop_in_room = [&](std::uint32_t id) {
    return std::any_of(room.props.begin(), room.props.end(),
                       [&](const PropRecord& p) { return p.id.value == id; });
  };
  if (dents.prop() ? !prop_in_room(dents.body_id()) : dents.body_id() != m->id.value) {
    ignore("dents for another body",
           dents.prop() ? "no such prop in its room" : "only a member's own avatar");
    return;
  }
  if (Status st =
          checkDents(dents.vertex_count(), repeatedSpan(dents.gaps()), repeatedSpan(dents.depths()),
                     static_cast<std::size_t>(config_.max_dent_vertices));
      !st) {
    ignore("malformed dents", st.error().message);
    return;
  }
  if (!std::isfinite(dents.server_time())) {
    ignore("malformed dents", "a time that is not finite");
    return;
  }
  // How often: per body and sender.
  const std::uint64_t key = dentsKey(dents.prop(), dents.body_id());
  auto sent = std::find_if(m->dents_sent_at.begin(), m->dents_sent_at.end(),
                           [&](const auto& e) { return e.first == key; });
  if (sent != m->dents_sent_at.end() && now - sent->second < config_.dents_interval_s) {
    ignore("dents too often",
           fmt::format("{:.3f} s after the last, faster than dents_interval_s {}",
                       now - sent->second, config_.dents_interval_s));
    return;
  }
  // How much: each message goes to the whole room.
  const auto bytes = static_cast<double>(dents.ByteSizeLong());
  if (!m->dents_bytes.take(now, bytes)) {
    ignore("dents over the byte rate", fmt::format("{:.0f} bytes past dents_bytes_per_s {:.0f}",
                                                   bytes, config_.dents_bytes_per_s));
    return;
  }
  if (sent == m->dents_sent_at.end()) {
    std::erase_if(m->dents_sent_at, [&](const auto& e) {  // props removed since
      return (e.first >> 32) != 0 && !prop_in_room(static_cast<std::uint32_t>(e.first));
    });
    m->dents_sent_at.emplace_back(key, now);
  } else {
    sent->second = now;
  }
  // Keep it as the body's newest and relay it.
  control::ServerMessage out;
  *out.mutable_dents() = dents;
  out.mutable_dents()->set_member(m->id.value);
  const std::string payload = out.SerializeAsString();
  std::vector<std::uint8_t>& frame = room.dents[key];
  frame.clear();
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()), frame);
  for (MemberId other : room.members) {
    if (other == m->id) continue;
    OutFrame& f = fx.frames.emplace_back();
    f.conn = members_.at(other.value).conn;
    f.bytes = frame;
  }
}

void Lobby::sendKeptDents(const RoomRecord& room, ConnId conn, Effects& fx) const {
  for (const auto& [key, frame] : room.dents) {
    OutFrame& f = fx.frames.emplace_back();
    f.conn = conn;
    f.bytes = frame;
  }
}

}  // namespace vistel::server
