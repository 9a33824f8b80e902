// The room list, as HTML (a page that works without scripts and refreshes itself every
// 5 s) and as JSON: every open room with its members and their ages. Names are escaped
// for HTML and JSON. Pure; O(rooms + members).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "server/core/lobby.hpp"

namespace vistel::server {

// Text safe inside HTML element content and quoted attribute values.
std::string htmlEscape(std::string_view text);

// A duration in seconds as "42 s", "3 min", "2 h 5 min".
std::string ageText(double seconds);

// `now` is the lobby clock of the views. hidden: rooms are not listed (join tokens are
// required and [web] public_room_list is off); the page says so.
std::string roomListHtml(const std::vector<LobbyRoomView>& rooms, double now, bool hidden);
std::string roomListJson(const std::vector<LobbyRoomView>& rooms, double now, bool hidden);

}  // namespace vistel::server
