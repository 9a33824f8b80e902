#include "server/web/web_pages.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace vistel::server {
namespace {

std::vector<const LobbyRoomView*> sortedByName(const std::vector<LobbyRoomView>& rooms) {
  std::vector<const LobbyRoomView*> sorted;
  for (const LobbyRoomView& r : rooms) sorted.push_back(&r);
  std::sort(sorted.begin(), sorted.end(),
            [](const LobbyRoomView* a, const LobbyRoomView* b) { return a->name < b->name; });
  return sorted;
}

}  // namespace

std::string htmlEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out.push_back(c);
    }
  }
  return out;
}

std::string ageText(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) seconds = 0.0;
  const auto s = static_cast<long long>(seconds);
  if (s < 60) return fmt::format("{} s", s);
  if (s < 3600) return fmt::format("{} min", s / 60);
  return fmt::format("{} h {} min", s / 3600, (s % 3600) / 60);
}

std::string roomListHtml(const std::vector<LobbyRoomView>& rooms, double now, bool hidden) {
  std::string body;
  if (hidden) {
    body =
        "<p>This server requires join tokens: the room list is not public. Open "
        "<code>/room/NAME?token=TOKEN</code> with a token for that room.</p>";
  } else if (rooms.empty()) {
    body = "<p class=\"empty\">No rooms are open. A room opens when its first member joins.</p>";
  } else {
    body = "<table><thead><tr><th>Room</th><th>Open for</th><th>Members</th></tr></thead><tbody>";
    for (const LobbyRoomView* r : sortedByName(rooms)) {
      std::string members;
      for (const LobbyMemberView& m : r->members) {
        if (!members.empty()) members += ", ";
        members += fmt::format("{} <span class=\"age\">({})</span>", htmlEscape(m.name),
                               ageText(now - m.joined_at));
      }
      body += fmt::format(
          "<tr><td><a href=\"/room/{0}\">{0}</a></td><td>{1}</td><td>{2}: {3}</td></tr>",
          htmlEscape(r->name), ageText(now - r->created_at), r->members.size(), members);
    }
    body += "</tbody></table>";
  }
  return fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
      "<meta http-equiv=\"refresh\" content=\"5\">"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
      "<title>vistel rooms</title><link rel=\"icon\" href=\"data:,\">"
      "<link rel=\"stylesheet\" href=\"/assets/style.css\"></head>"
      "<body class=\"list\"><h1>vistel rooms</h1>{}"
      "<p class=\"note\">Click a room to watch it in 3D. This list refreshes every 5 s.</p>"
      "</body></html>\n",
      body);
}

std::string roomListJson(const std::vector<LobbyRoomView>& rooms, double now, bool hidden) {
  nlohmann::json list = nlohmann::json::array();
  if (!hidden) {
    for (const LobbyRoomView* r : sortedByName(rooms)) {
      nlohmann::json members = nlohmann::json::array();
      for (const LobbyMemberView& m : r->members) {
        members.push_back({{"id", m.id}, {"name", m.name}, {"age_s", now - m.joined_at}});
      }
      list.push_back({{"name", r->name}, {"age_s", now - r->created_at}, {"members", members}});
    }
  }
  return nlohmann::json{{"hidden", hidden}, {"rooms", list}}.dump(
             -1, ' ', false, nlohmann::json::error_handler_t::replace) +
         "\n";
}

}  // namespace vistel::server
