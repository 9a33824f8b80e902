// libFuzzer target: the HTTP endpoint's request-head parser and the SDK client's response
// parser (server/http/http_message.hpp) on arbitrary bytes. Meant for tests/fuzz (move it
// there and add `vistel_fuzz_target(fuzz_http DEPS vistel_server_http)`; it is kept here
// because tests/fuzz belongs to another owner).
//
// Properties: nothing crashes or reads out of bounds; a rejected head names 400, 431 or
// 505; an accepted head has a token method, a path starting with '/', HTTP/1.0 or 1.1;
// routing it gives a response whose bytes parse back with the same status and body; the
// response parser accepts or rejects any bytes without crashing, and a HEAD answer has no
// body.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "server/http/http_message.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using namespace vistel::server;
using fuzz::check;

std::vector<fuzz::Seed> makeSeeds() {
  return {
      fuzz::textSeed("get_metrics",
                     "GET /metrics HTTP/1.1\r\nHost: 127.0.0.1:9100\r\n"
                     "User-Agent: Prometheus/2.45\r\nAccept: text/plain\r\n\r\n"),
      fuzz::textSeed("head_readyz", "HEAD /readyz?x=1 HTTP/1.0\r\n\r\n"),
      fuzz::textSeed("absolute", "GET http://h:1/healthz HTTP/1.1\r\nHost: h:1\r\n\r\n"),
      fuzz::textSeed("post_body",
                     "POST /metrics HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\n\r\n{}"),
      fuzz::textSeed("response_chunked",
                     "HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0\r\n\r\n"),
      fuzz::textSeed("response_length",
                     "HTTP/1.1 503 Service Unavailable\r\nContent-Length: 3\r\n"
                     "\r\nno\n"),
  };
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);

  // Request heads, as the endpoint cuts them.
  std::string_view head = bytes;
  if (auto end = findHeadEnd(bytes)) head = bytes.substr(0, *end);
  auto request = parseRequestHead(head);
  if (!request) {
    int status = statusOfParseError(request.error());
    check(status == 400 || status == 431 || status == 505, "a rejection names 400, 431 or 505");
  } else {
    check(!request->method.empty() && request->method.size() <= 16, "a method token");
    check(!request->path.empty() && request->path.front() == '/', "a path starting with '/'");
    check(request->version_minor == 0 || request->version_minor == 1, "HTTP/1.0 or 1.1");
    HttpRoutes routes{[] { return true; }};
    if (auto response = routeRequest(*request, routes)) {
      auto back = parseResponse(serializeResponse(*response, false));
      check(back.ok(), "our response parses");
      check(back->status == response->status, "the status round-trips");
      check(back->body == response->body, "the body round-trips");
    }
  }

  // Responses, as the SDK client reads them.
  auto response = parseResponse(bytes);
  if (response) check(response->status >= 100, "a parsed status is at least 100");
  auto head_response = parseResponse(bytes, true);
  if (head_response) check(head_response->body.empty(), "a HEAD answer has no body");
  return 0;
}
