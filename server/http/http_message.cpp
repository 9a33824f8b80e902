// HTTP/1.1 message syntax (RFC 9112 §2-3, §6; field syntax RFC 9110 §5), the strict
// subset a health and metrics endpoint needs.
#include "server/http/http_message.hpp"

#include <charconv>

#include <fmt/format.h>

namespace vistel::server {
namespace {

constexpr std::size_t kMaxMethodBytes = 16;
constexpr std::size_t kMaxTargetBytes = 2048;
constexpr std::size_t kMaxHeaderCount = 64;
constexpr std::size_t kMaxChunkedBodyBytes = 1u << 20;

// tchar (RFC 9110 §5.6.2): the characters of a method or a field name.
bool isTchar(char c) {
  if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) return true;
  switch (c) {
    case '!':
    case '#':
    case '$':
    case '%':
    case '&':
    case '\'':
    case '*':
    case '+':
    case '-':
    case '.':
    case '^':
    case '_':
    case '`':
    case '|':
    case '~':
      return true;
    default:
      return false;
  }
}

bool isToken(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s) {
    if (!isTchar(c)) return false;
  }
  return true;
}

// A field value's bytes: visible ASCII, obs-text (>= 0x80), space and tab.
bool isFieldValueChar(char c) {
  auto u = static_cast<unsigned char>(c);
  return u == '\t' || (u >= 0x20 && u != 0x7f);
}

std::string toLower(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

std::string_view trimOws(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// Splits "a\r\nb\r\n" into lines; every CR must be followed by LF and every LF preceded
// by CR (no bare CR or LF: they enable request smuggling between lenient parsers).
Result<std::vector<std::string_view>> splitLines(std::string_view bytes) {
  std::vector<std::string_view> lines;
  std::size_t start = 0;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    if (bytes[i] == '\r') {
      if (i + 1 >= bytes.size() || bytes[i + 1] != '\n') return fail("400 bare CR in head");
      lines.push_back(bytes.substr(start, i - start));
      ++i;
      start = i + 1;
    } else if (bytes[i] == '\n') {
      return fail("400 bare LF in head");
    } else if (bytes[i] == '\0') {
      return fail("400 NUL byte in head");
    }
  }
  if (start != bytes.size()) lines.push_back(bytes.substr(start));
  return lines;
}

// "Name: value" with the name a token and no whitespace before the colon.
Result<std::pair<std::string, std::string>> parseField(std::string_view line) {
  if (line.front() == ' ' || line.front() == '\t') {
    return fail("400 folded header line (obsolete line folding)");
  }
  std::size_t colon = line.find(':');
  if (colon == std::string_view::npos) return fail("400 header line without ':'");
  std::string_view name = line.substr(0, colon);
  if (!isToken(name)) return fail("400 bad header name");
  std::string_view value = trimOws(line.substr(colon + 1));
  for (char c : value) {
    if (!isFieldValueChar(c)) return fail("400 control character in header value");
  }
  return std::pair<std::string, std::string>{toLower(name), std::string(value)};
}

Result<int> parseVersion(std::string_view version) {
  if (version.size() != 8 || version.substr(0, 5) != "HTTP/" || version[6] != '.' ||
      version[5] < '0' || version[5] > '9' || version[7] < '0' || version[7] > '9') {
    return fail("400 bad HTTP version");
  }
  if (version[5] != '1' || (version[7] != '0' && version[7] != '1')) {
    return fail("505 HTTP version not supported");
  }
  return version[7] - '0';
}

// Origin-form "/path?query", or absolute-form "http://authority/path?query" (servers
// must accept it, RFC 9112 §3.2.2). Sets path and query.
Status parseTarget(std::string_view target, HttpRequestHead& out) {
  if (target.empty() || target.size() > kMaxTargetBytes) return fail("400 bad request target");
  for (char c : target) {
    auto u = static_cast<unsigned char>(c);
    if (u <= 0x20 || u >= 0x7f) return fail("400 bad character in request target");
  }
  bool absolute = false;
  for (std::string_view scheme : {std::string_view("http://"), std::string_view("https://")}) {
    if (target.size() >= scheme.size() && toLower(target.substr(0, scheme.size())) == scheme) {
      std::string_view rest = target.substr(scheme.size());
      std::size_t slash = rest.find_first_of("/?");
      if (slash == 0 || rest.empty()) return fail("400 absolute target without authority");
      target = slash == std::string_view::npos ? std::string_view("/") : rest.substr(slash);
      absolute = true;
      break;
    }
  }
  // An absolute target may go straight to the query ("http://host?x"): the path is "/".
  if (target.front() != '/' && !(absolute && target.front() == '?')) {
    return fail("400 request target is not a path");
  }
  std::size_t question = target.find('?');
  std::string_view path = target.substr(0, question);
  out.path.assign(path.empty() ? std::string_view("/") : path);
  if (question != std::string_view::npos) out.query.assign(target.substr(question + 1));
  return {};
}

}  // namespace

std::optional<std::size_t> findHeadEnd(std::string_view bytes) {
  std::size_t at = bytes.find("\r\n\r\n");
  if (at == std::string_view::npos) return std::nullopt;
  return at + 4;
}

Result<HttpRequestHead> parseRequestHead(std::string_view head) {
  if (head.size() > kMaxRequestHeadBytes) return fail("431 request head too large");
  auto lines = splitLines(head);
  if (!lines) return lines.error();
  // A server should ignore empty lines before the request line (RFC 9112 §2.2).
  std::size_t first = 0;
  while (first < lines->size() && (*lines)[first].empty() && first < 2) ++first;
  if (first >= lines->size() || (*lines)[first].empty()) return fail("400 missing request line");

  // Request line: method SP target SP version, single spaces.
  HttpRequestHead request;
  std::string_view line = (*lines)[first];
  std::size_t sp1 = line.find(' ');
  std::size_t sp2 = sp1 == std::string_view::npos ? sp1 : line.find(' ', sp1 + 1);
  if (sp2 == std::string_view::npos || line.find(' ', sp2 + 1) != std::string_view::npos) {
    return fail("400 malformed request line");
  }
  std::string_view method = line.substr(0, sp1);
  if (!isToken(method) || method.size() > kMaxMethodBytes) return fail("400 bad method");
  request.method = std::string(method);
  if (Status st = parseTarget(line.substr(sp1 + 1, sp2 - sp1 - 1), request); !st) {
    return st.error();
  }
  auto minor = parseVersion(line.substr(sp2 + 1));
  if (!minor) return minor.error();
  request.version_minor = *minor;

  // Header fields up to the blank line; nothing may follow it here.
  bool blank_seen = false;
  int host_count = 0;
  for (std::size_t i = first + 1; i < lines->size(); ++i) {
    std::string_view field_line = (*lines)[i];
    if (field_line.empty()) {
      blank_seen = true;
      if (i + 1 != lines->size()) return fail("400 bytes after the head");
      break;
    }
    if (request.headers.size() >= kMaxHeaderCount) return fail("431 too many header fields");
    auto field = parseField(field_line);
    if (!field) return field.error();
    if (field->first == "host") ++host_count;
    if (field->first == "transfer-encoding") return fail("400 request bodies are not accepted");
    if (field->first == "content-length" && field->second != "0") {
      return fail("400 request bodies are not accepted");
    }
    request.headers.push_back(std::move(*field));
  }
  if (!blank_seen) return fail("400 head does not end with a blank line");
  if (host_count > 1) return fail("400 more than one Host header");
  if (request.version_minor == 1 && host_count == 0) return fail("400 HTTP/1.1 without Host");
  return request;
}

int statusOfParseError(const Error& error) {
  int status = 0;
  const std::string& m = error.message;
  auto [ptr, ec] = std::from_chars(m.data(), m.data() + std::min<std::size_t>(3, m.size()), status);
  if (ec != std::errc() || ptr != m.data() + 3 || status < 400 || status > 599) return 400;
  return status;
}

HttpResponse plainResponse(int status, std::string_view body) {
  HttpResponse response;
  response.status = status;
  response.body = std::string(body);
  if (response.body.empty() || response.body.back() != '\n') response.body.push_back('\n');
  return response;
}

std::optional<HttpResponse> routeRequest(const HttpRequestHead& request, const HttpRoutes& routes) {
  const bool known =
      request.path == "/healthz" || request.path == "/readyz" || request.path == "/metrics";
  if (!known) return plainResponse(404, "not found");
  if (request.method != "GET" && request.method != "HEAD") {
    HttpResponse response = plainResponse(405, "method not allowed");
    response.extra_headers.emplace_back("Allow", "GET, HEAD");
    return response;
  }
  if (request.path == "/healthz") return plainResponse(200, "ok");
  if (request.path == "/readyz") {
    bool ready = routes.ready && routes.ready();
    return ready ? plainResponse(200, "ready") : plainResponse(503, "not ready");
  }
  return std::nullopt;  // /metrics
}

std::string_view reasonPhrase(int status) {
  switch (status) {
    case 200:
      return "OK";
    case 204:
      return "No Content";
    case 400:
      return "Bad Request";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 408:
      return "Request Timeout";
    case 413:
      return "Content Too Large";
    case 431:
      return "Request Header Fields Too Large";
    case 500:
      return "Internal Server Error";
    case 503:
      return "Service Unavailable";
    case 505:
      return "HTTP Version Not Supported";
    default:
      return "Unknown";
  }
}

std::string serializeResponse(const HttpResponse& response, bool head_only) {
  std::string out = fmt::format(
      "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n"
      "Cache-Control: no-store\r\n",
      response.status, reasonPhrase(response.status), response.content_type, response.body.size());
  for (const auto& [name, value] : response.extra_headers) {
    out += fmt::format("{}: {}\r\n", name, value);
  }
  out += "\r\n";
  if (!head_only) out += response.body;
  return out;
}

Result<HttpClientResponse> parseResponse(std::string_view bytes, bool head_request) {
  auto end = findHeadEnd(bytes);
  if (!end) return fail("response without a complete head ({} bytes)", bytes.size());
  auto lines = splitLines(bytes.substr(0, *end));
  if (!lines) return fail("bad response head: {}", lines.error().message.substr(4));
  if (lines->empty()) return fail("empty response head");

  // Status line: HTTP/1.x SP 3DIGIT SP reason.
  HttpClientResponse response;
  std::string_view status_line = (*lines)[0];
  if (status_line.size() < 12 || status_line.substr(0, 7) != "HTTP/1." || status_line[8] != ' ') {
    return fail("bad status line '{}'", status_line.substr(0, 64));
  }
  auto [ptr, ec] =
      std::from_chars(status_line.data() + 9, status_line.data() + 12, response.status);
  if (ec != std::errc() || ptr != status_line.data() + 12 || response.status < 100) {
    return fail("bad status code in '{}'", status_line.substr(0, 64));
  }
  for (std::size_t i = 1; i < lines->size(); ++i) {
    if ((*lines)[i].empty()) break;
    auto field = parseField((*lines)[i]);
    if (!field) return fail("bad response header: {}", field.error().message.substr(4));
    response.headers.push_back(std::move(*field));
  }

  // Body: none for HEAD, else chunked, Content-Length, or up to the close.
  if (head_request) return response;
  std::string_view body = bytes.substr(*end);
  std::optional<std::size_t> content_length;
  bool chunked = false;
  for (const auto& [name, value] : response.headers) {
    if (name == "transfer-encoding" && toLower(value).find("chunked") != std::string::npos) {
      chunked = true;
    }
    if (name == "content-length") {
      std::size_t n = 0;
      auto [p, e] = std::from_chars(value.data(), value.data() + value.size(), n);
      if (e != std::errc() || p != value.data() + value.size()) {
        return fail("bad Content-Length '{}'", value.substr(0, 32));
      }
      content_length = n;
    }
  }
  if (chunked) {
    while (true) {
      std::size_t eol = body.find("\r\n");
      if (eol == std::string_view::npos) return fail("truncated chunk size line");
      std::string_view size_text = body.substr(0, body.find_first_of(";\r"));
      std::size_t size = 0;
      auto [p, e] =
          std::from_chars(size_text.data(), size_text.data() + size_text.size(), size, 16);
      if (e != std::errc() || p != size_text.data() + size_text.size()) {
        return fail("bad chunk size");
      }
      body.remove_prefix(eol + 2);
      if (size == 0) break;
      if (size > body.size() || response.body.size() + size > kMaxChunkedBodyBytes) {
        return fail("truncated or oversized chunk");
      }
      response.body.append(body.substr(0, size));
      body.remove_prefix(size);
      if (body.substr(0, 2) != "\r\n") return fail("chunk without CRLF");
      body.remove_prefix(2);
    }
  } else if (content_length) {
    if (body.size() < *content_length) {
      return fail("body shorter than Content-Length ({} < {})", body.size(), *content_length);
    }
    response.body = std::string(body.substr(0, *content_length));
  } else {
    response.body = std::string(body);
  }
  return response;
}

std::string serializeRequest(std::string_view method, std::string_view target,
                             std::string_view host, std::string_view body) {
  std::string out =
      fmt::format("{} {} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n", method, target, host);
  if (!body.empty() || method == "POST" || method == "PUT" || method == "PATCH") {
    out += fmt::format("Content-Type: application/json\r\nContent-Length: {}\r\n", body.size());
  }
  out += "\r\n";
  out += body;
  return out;
}

}  // namespace vistel::server
