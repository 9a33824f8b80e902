// Lobby::roomViews / roomView: what spectators (server/web) may see of the rooms.
#include "server/core/lobby.hpp"

namespace vistel::server {

LobbyRoomView Lobby::viewOf(const RoomRecord& room) const {
  LobbyRoomView view;
  view.id = room.id.value;
  view.name = room.name;
  view.created_at = room.created_at;
  view.members.reserve(room.members.size());
  for (MemberId id : room.members) {
    auto it = members_.find(id.value);
    if (it == members_.end()) continue;
    const Member& m = it->second;
    view.members.push_back(
        {m.id.value, m.name, m.avatar_hash, m.avatar_ready, m.seat, m.joined_at});
  }
  return view;
}

std::vector<LobbyRoomView> Lobby::roomViews() const {
  std::vector<LobbyRoomView> views;
  views.reserve(rooms_.size());
  for (const auto& [id, room] : rooms_) views.push_back(viewOf(room));
  return views;
}

std::optional<LobbyRoomView> Lobby::roomView(std::string_view name) const {
  auto it = room_by_name_.find(std::string(name));
  if (it == room_by_name_.end()) return std::nullopt;
  auto room = rooms_.find(it->second);
  if (room == rooms_.end()) return std::nullopt;
  return viewOf(room->second);
}

}  // namespace vistel::server
