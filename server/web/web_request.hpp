// The spectator web server's request handling that needs no socket: the request-head
// parser's limits, request targets (paths, query parameters, percent escapes) and the
// decision what a request gets. Every function takes any bytes: bad input gets an error
// or a 4xx status, never a crash. Pure; cost linear in the input.
//
// Public paths (GET only; anything else is 405 with "Allow: GET"):
//   /                       the room list (HTML)
//   /api/rooms              the room list (JSON)
//   /room/NAME              the spectator page of room NAME
//   /ws/room/NAME?token=T   the WebSocket of room NAME (an upgrade; 426 without one)
//   /avatar/HASH.glb        an avatar by content hash (64 lowercase hex)
//   /assets/FILE            a static asset embedded at build time
// A room NAME is what the lobby accepts (1-64 of [A-Za-z0-9_.-]) except "." and "..".
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"

namespace vistel::server {

inline constexpr std::size_t kMaxTargetBytes = 2048;  // longer targets: 414

enum class WebRoute { kRoomList, kRoomsJson, kRoomPage, kRoomSocket, kAvatar, kAsset, kNotFound };

struct WebTarget {
  WebRoute route = WebRoute::kNotFound;
  std::string room;   // kRoomPage, kRoomSocket: the room's name
  std::string hash;   // kAvatar: 64 lowercase hex
  std::string asset;  // kAsset: the file name after /assets/
  std::string token;  // the query's `token` parameter (decoded), or empty
};

// %XX escapes decoded (and '+' as a space when plus_is_space). Errors: a truncated or
// non-hex escape, a decoded NUL or other control character.
Result<std::string> percentDecode(std::string_view text, bool plus_is_space);

// The first `key=value` of a query string ("a=1&b=2", without the '?'), value decoded;
// nullopt when absent or badly escaped.
std::optional<std::string> queryParam(std::string_view query, std::string_view key);

// True for a room name the web server serves (see above).
bool webRoomName(std::string_view name);

// Parses an origin-form target ("/path?query"). Errors (each a 400 but the first):
// longer than kMaxTargetBytes (414), not starting with '/', a bad escape in the path, a
// dot segment or an empty segment. An unknown path is route kNotFound, not an error.
Result<WebTarget> parseTarget(std::string_view target);

// What a parsed request head gets before its route is served.
struct RequestHead {
  std::string method;  // as sent (case-sensitive: "GET")
  std::string target;
  bool has_body = false;    // Content-Length > 0 or Transfer-Encoding
  bool is_upgrade = false;  // a WebSocket upgrade request
  std::string host;         // the Host header ("" when absent)
  std::string origin;       // the Origin header ("" when absent: not a browser's page)
};
struct RequestVerdict {
  int status = 0;      // 0: go on and serve `target`; else the error status to answer
  std::string reason;  // short text for the response body and the log
  WebTarget target;
};
// 405 for a method other than GET, 413 for a body, 414/400 for a bad target, 404 for an
// unknown path, 426 for a GET of a WebSocket path without an upgrade, 400 for an upgrade
// anywhere else, 403 for an upgrade from another site's page (an Origin other than
// http(s)://HOST: a page elsewhere must not open spectator sockets in a visitor's browser).
RequestVerdict judgeRequest(const RequestHead& head);

// Parses a complete request head (request line, headers, the blank line) as the server
// does, with its limit of max_header_bytes; bytes after the head are not looked at (a
// body is judgeRequest's to refuse). Errors carry the status to answer: 400 (malformed
// or incomplete), 431 (too large).
struct ParsedHead {
  RequestHead head;
  bool keep_alive = false;
  int version = 11;  // 10 or 11
};
struct HeadError {
  int status = 400;
  std::string message;
};
std::optional<ParsedHead> parseRequestHead(std::string_view bytes, std::size_t max_header_bytes,
                                           HeadError* error);

// DNS-rebinding defence: whether a Host header names this server. Allowed: no Host at all
// (not a browser's request: HTTP/1.0 tools), an IP address literal (IPv4, or IPv6 in
// brackets) with any port, "localhost" with any port, and the names in `allowed` (each
// "name", any port, or "name:port"; case-insensitive; a trailing dot ignored). Not
// allowed: any other name, a malformed Host (bad characters, a port that is not 1-65535).
// A page served under a name whose DNS an attacker points at this server then gets no
// answer (the server answers 421). IP literals and localhost cannot be rebound. Pure.
bool hostAllowed(std::string_view host, std::span<const std::string> allowed);

// [web] allowed_hosts: names (or name:port) separated by commas or spaces, lowercased.
// Errors name the entry that is not a host name (letters, digits, '-', '.'; a port
// 1-65535).
Result<std::vector<std::string>> parseAllowedHosts(std::string_view text);

// The standard reason phrase of an HTTP status ("Not Found"); "Error" for one unknown.
std::string_view statusText(int status);

}  // namespace vistel::server
