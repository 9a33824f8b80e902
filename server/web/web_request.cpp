#include "server/web/web_request.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <string>

#include "server/web/web_beast.hpp"

namespace vistel::server {
namespace {

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool isContentHashText(std::string_view h) {
  return h.size() == 64 && std::all_of(h.begin(), h.end(), [](char c) {
           return hexValue(c) >= 0 && !std::isupper(static_cast<unsigned char>(c));
         });
}

bool assetName(std::string_view name) {
  if (name.empty() || name.size() > 64 || name.front() == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  });
}

}  // namespace

Result<std::string> percentDecode(std::string_view text, bool plus_is_space) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (c == '%') {
      if (i + 2 >= text.size() || hexValue(text[i + 1]) < 0 || hexValue(text[i + 2]) < 0) {
        return fail("bad percent escape at byte {}", i + 1);
      }
      c = static_cast<char>(hexValue(text[i + 1]) * 16 + hexValue(text[i + 2]));
      i += 2;
    } else if (c == '+' && plus_is_space) {
      c = ' ';
    }
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) return fail("control character (0x{:02x}) at byte {}", u, i + 1);
    out.push_back(c);
  }
  return out;
}

std::optional<std::string> queryParam(std::string_view query, std::string_view key) {
  while (!query.empty()) {
    const std::size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view{} : query.substr(amp + 1);
    const std::size_t eq = pair.find('=');
    const std::string_view k = pair.substr(0, eq);
    if (k != key) continue;
    auto value = percentDecode(
        eq == std::string_view::npos ? std::string_view{} : pair.substr(eq + 1), true);
    if (!value) return std::nullopt;
    return std::move(*value);
  }
  return std::nullopt;
}

bool webRoomName(std::string_view name) {
  if (name.empty() || name.size() > 64 || name == "." || name == "..") return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
  });
}

Result<WebTarget> parseTarget(std::string_view target) {
  if (target.size() > kMaxTargetBytes) {
    return fail("request target of {} bytes (at most {})", target.size(), kMaxTargetBytes);
  }
  if (target.empty() || target.front() != '/') return fail("request target must start with '/'");
  const std::size_t question = target.find('?');
  const std::string_view raw_path = target.substr(0, question);
  const std::string_view query =
      question == std::string_view::npos ? std::string_view{} : target.substr(question + 1);
  auto path = percentDecode(raw_path, false);
  if (!path) return fail("path: {}", path.error().message);

  // Segments: none empty (but a trailing '/' on "/"), no dot segments.
  std::array<std::string_view, 4> segments{};
  std::size_t count = 0;
  std::string_view rest = std::string_view(*path).substr(1);
  while (!rest.empty()) {
    const std::size_t slash = rest.find('/');
    const std::string_view segment = rest.substr(0, slash);
    if (segment.empty()) return fail("empty path segment");
    if (segment == "." || segment == "..") return fail("dot segment in the path");
    if (count == segments.size()) {
      count = segments.size() + 1;  // too deep for any route
      break;
    }
    segments[count++] = segment;
    if (slash == std::string_view::npos) break;
    rest = rest.substr(slash + 1);
    if (rest.empty()) return fail("empty path segment");
  }

  WebTarget t;
  if (auto token = queryParam(query, "token")) t.token = std::move(*token);
  if (count == 0) {
    t.route = WebRoute::kRoomList;
  } else if (count == 2 && segments[0] == "api" && segments[1] == "rooms") {
    t.route = WebRoute::kRoomsJson;
  } else if (count == 2 && segments[0] == "room" && webRoomName(segments[1])) {
    t.route = WebRoute::kRoomPage;
    t.room = segments[1];
  } else if (count == 3 && segments[0] == "ws" && segments[1] == "room" &&
             webRoomName(segments[2])) {
    t.route = WebRoute::kRoomSocket;
    t.room = segments[2];
  } else if (count == 2 && segments[0] == "avatar" && segments[1].size() == 68 &&
             segments[1].ends_with(".glb") && isContentHashText(segments[1].substr(0, 64))) {
    t.route = WebRoute::kAvatar;
    t.hash = segments[1].substr(0, 64);
  } else if (count == 2 && segments[0] == "assets" && assetName(segments[1])) {
    t.route = WebRoute::kAsset;
    t.asset = segments[1];
  }
  return t;
}

RequestVerdict judgeRequest(const RequestHead& head) {
  RequestVerdict v;
  if (head.method != "GET") {
    v.status = 405;
    v.reason = "only GET is served";
    return v;
  }
  if (head.has_body) {
    v.status = 413;
    v.reason = "a GET carries no body";
    return v;
  }
  auto target = parseTarget(head.target);
  if (!target) {
    v.status = head.target.size() > kMaxTargetBytes ? 414 : 400;
    v.reason = target.error().message;
    return v;
  }
  v.target = std::move(*target);
  if (v.target.route == WebRoute::kNotFound) {
    v.status = 404;
    v.reason = "no such page";
  } else if (v.target.route == WebRoute::kRoomSocket && !head.is_upgrade) {
    v.status = 426;
    v.reason = "a WebSocket path: upgrade required";
  } else if (v.target.route != WebRoute::kRoomSocket && head.is_upgrade) {
    v.status = 400;
    v.reason = "no WebSocket here";
  } else if (v.target.route == WebRoute::kRoomSocket && !head.origin.empty() &&
             head.origin != "http://" + head.host && head.origin != "https://" + head.host) {
    v.status = 403;
    v.reason = "a WebSocket from another site's page";
  }
  return v;
}

std::optional<ParsedHead> parseRequestHead(std::string_view bytes, std::size_t max_header_bytes,
                                           HeadError* error) {
  HeadParser parser;
  configureHeadParser(parser, max_header_bytes);
  boost::system::error_code ec;
  std::size_t used = 0;
  // As the socket reader does: the parser sees the bytes it has not taken yet.
  while (!ec && used < bytes.size() && !parser.is_header_done()) {
    const std::size_t n = parser.put(asio::buffer(bytes.data() + used, bytes.size() - used), ec);
    if (n == 0 && !ec) break;  // needs more bytes than there are
    used += n;
  }
  if (!ec && !parser.is_header_done()) ec = http::error::need_more;
  if (ec) {
    if (error != nullptr) {
      error->status = ec == http::error::need_more ? 400 : statusOfParseError(ec);
      error->message = ec.message();
    }
    return std::nullopt;
  }
  const auto& req = parser.get();
  ParsedHead parsed;
  parsed.head = requestHeadOf(req);
  parsed.keep_alive = req.keep_alive();
  parsed.version = static_cast<int>(req.version());
  return parsed;
}

namespace {

// A Host value split into its lowercased name and its port (0: none); false when malformed.
struct HostParts {
  std::string name;  // IPv6 without brackets
  bool ipv6 = false;
  int port = 0;
};
bool splitHost(std::string_view host, HostParts& out) {
  std::string_view name = host;
  std::string_view port;
  if (host.starts_with('[')) {
    const auto close = host.find(']');
    if (close == std::string_view::npos) return false;
    name = host.substr(1, close - 1);
    const std::string_view rest = host.substr(close + 1);
    if (!rest.empty()) {
      if (rest[0] != ':') return false;
      port = rest.substr(1);
    }
    out.ipv6 = true;
  } else if (const auto colon = host.rfind(':'); colon != std::string_view::npos) {
    name = host.substr(0, colon);
    port = host.substr(colon + 1);
  }
  if (name.empty() || name.size() > 253) return false;
  out.name.clear();
  for (char c : name) {
    const char lower = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const bool ok = (lower >= 'a' && lower <= 'z') || (lower >= '0' && lower <= '9') ||
                    lower == '-' || lower == '.' || (out.ipv6 && lower == ':');
    if (!ok) return false;
    out.name.push_back(lower);
  }
  if (!out.ipv6 && out.name.size() > 1 && out.name.back() == '.') out.name.pop_back();
  out.port = 0;
  if (host.size() > 0 && host.back() == ':' && port.empty()) return false;
  if (!port.empty()) {
    if (port.size() > 5) return false;
    for (char c : port) {
      if (c < '0' || c > '9') return false;
      out.port = out.port * 10 + (c - '0');
    }
    if (out.port < 1 || out.port > 65535) return false;
  }
  return true;
}

bool ipLiteral(const HostParts& parts) {
  beast::error_code ec;
  const auto address = asio::ip::make_address(parts.name, ec);
  return !ec && address.is_v6() == parts.ipv6;
}

}  // namespace

bool hostAllowed(std::string_view host, std::span<const std::string> allowed) {
  if (host.empty()) return true;
  HostParts parts;
  if (!splitHost(host, parts)) return false;
  if (ipLiteral(parts) || parts.name == "localhost") return true;
  for (const std::string& entry : allowed) {
    HostParts want;
    if (!splitHost(entry, want)) continue;
    if (want.name == parts.name && (want.port == 0 || want.port == parts.port)) return true;
  }
  return false;
}

Result<std::vector<std::string>> parseAllowedHosts(std::string_view text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at < text.size()) {
    const auto end = text.find_first_of(", \t", at);
    const std::string_view entry =
        text.substr(at, end == std::string_view::npos ? text.npos : end - at);
    at = end == std::string_view::npos ? text.size() : end + 1;
    if (entry.empty()) continue;
    HostParts parts;
    if (!splitHost(entry, parts)) {
      return fail("allowed_hosts: '{}' is not a host name or host:port", entry);
    }
    std::string name = parts.ipv6 ? "[" + parts.name + "]" : parts.name;
    out.push_back(parts.port == 0 ? name : name + ":" + std::to_string(parts.port));
  }
  return out;
}

std::string_view statusText(int status) {
  if (status < 100 || status > 999) return "Error";
  const http::status known = http::int_to_status(static_cast<unsigned>(status));
  if (known == http::status::unknown) return "Error";
  const auto reason = http::obsolete_reason(known);  // Beast's table of the standard phrases
  return {reason.data(), reason.size()};
}

}  // namespace vistel::server
