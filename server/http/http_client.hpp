// One HTTP/1.1 request over a fresh TCP connection (Connection: close), asynchronous on
// an io_context, with a deadline over the whole exchange and a bound on the response
// size. Made for talking to a sidecar on localhost (the Agones SDK gateway), so the host
// must be an IP address literal or "localhost" (no DNS lookups).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "common/base/result.hpp"
#include "server/http/http_message.hpp"
#include "server/shell/asio.hpp"

namespace vistel::server {

struct HttpClientRequest {
  std::string host = "127.0.0.1";  // IP literal, or "localhost" (= 127.0.0.1)
  std::uint16_t port = 80;
  std::string method = "GET";
  std::string target = "/";
  std::string body;                           // sent as application/json when set
  double timeout_s = 2.0;                     // connect + write + read, in seconds
  std::size_t max_response_bytes = 1u << 20;  // longer responses fail
};

using HttpClientCallback = std::function<void(Result<HttpClientResponse>)>;

// Starts the exchange; done is called exactly once on an io_context thread with the
// parsed response (any status) or an Error naming the step ("connect", "timed out ...").
void httpRequest(asio::io_context& io, HttpClientRequest request, HttpClientCallback done);

}  // namespace vistel::server
