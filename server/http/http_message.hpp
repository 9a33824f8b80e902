// The pure part of the small HTTP/1.1 endpoint and client (RFC 9112 message syntax):
// finding the end of a request head, parsing a request head strictly, routing it to a
// response, writing a response, and parsing a response a client read. No sockets here:
// every function takes bytes and returns values, so each is unit-tested on its own.
//
// Requests come from the network and may be malicious: parsing never asserts, bounds
// every length, and refuses what it does not need (bodies, folded headers, NUL, bare CR,
// non-ASCII in the request line) with a 4xx response.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/base/result.hpp"

namespace vistel::server {

// Largest request head the endpoint reads (request line + headers + blank line).
inline constexpr std::size_t kMaxRequestHeadBytes = 8u << 10;

// A parsed request head. path is the target without the query ("/metrics").
struct HttpRequestHead {
  std::string method;     // "GET", "HEAD", ... (case-sensitive token)
  std::string path;       // origin-form, starts with '/'
  std::string query;      // after '?', without it (may be empty)
  int version_minor = 1;  // HTTP/1.<version_minor>: 0 or 1
  std::vector<std::pair<std::string, std::string>> headers;  // names lower-cased, values trimmed
};

// A response before it is written. Every response closes the connection.
struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> extra_headers;  // e.g. {"Allow", "GET, HEAD"}
};

// Where the head ends in what has been read so far: the offset just past the first
// "\r\n\r\n", or nullopt when it is not there yet. Cost: linear.
std::optional<std::size_t> findHeadEnd(std::string_view bytes);

// Parses a complete head (up to and including the blank line). On bad input the Error's
// message starts with the status to answer and a reason: "400 ...", "505 ...",
// "431 ...". Accepts HTTP/1.0 and HTTP/1.1; HTTP/1.1 requires a Host header; a request
// with a body (Content-Length other than 0, or Transfer-Encoding) is refused with 400
// since no route takes one.
Result<HttpRequestHead> parseRequestHead(std::string_view head);

// The status the error of parseRequestHead names (400 when it names none).
int statusOfParseError(const Error& error);

// What the endpoint's routes need from the server. Both may be called on any I/O thread.
struct HttpRoutes {
  std::function<bool()> ready;  // /readyz: 200 when true, 503 otherwise; absent: 503
};

// Route of a parsed request that needs no asynchronous work: /healthz, /readyz, 404,
// 405. Returns nullopt for GET/HEAD /metrics (the endpoint asks its metrics provider).
std::optional<HttpResponse> routeRequest(const HttpRequestHead& request, const HttpRoutes& routes);

// A response for a status with a one-line plain-text body ("not found\n").
HttpResponse plainResponse(int status, std::string_view body);

// The bytes of a response: status line, Content-Type, Content-Length, Connection: close,
// Cache-Control: no-store, extra headers, blank line, and the body unless head_only.
std::string serializeResponse(const HttpResponse& response, bool head_only);

// "OK", "Not Found", ... for the statuses used here ("Unknown" otherwise).
std::string_view reasonPhrase(int status);

// A response as a client reads it (the Agones SDK client, the tests).
struct HttpClientResponse {
  int status = 0;
  std::vector<std::pair<std::string, std::string>> headers;  // names lower-cased
  std::string body;
};

// Parses a whole response read until the server closed the connection. Honours
// Content-Length when present (the body is cut to it; fewer bytes is an error) and
// decodes Transfer-Encoding: chunked; otherwise the body is everything after the head.
// The response to a HEAD request has no body whatever its headers say (head_request).
Result<HttpClientResponse> parseResponse(std::string_view bytes, bool head_request = false);

// The bytes of a client request with Host, Connection: close, and, when body is not
// empty or the method is POST/PUT/PATCH, Content-Type: application/json and
// Content-Length.
std::string serializeRequest(std::string_view method, std::string_view target,
                             std::string_view host, std::string_view body);

}  // namespace vistel::server
