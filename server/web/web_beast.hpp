// The one place server/web includes Boost.Beast (after server/shell/asio.hpp, which
// includes <utility> first for Boost 1.74 under g++ 12 C++20), and the request parser's
// setup shared by the server and parseRequestHead.
#pragma once

#include "server/shell/asio.hpp"

#include <cstdint>
#include <limits>

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "server/web/web_request.hpp"

namespace vistel::server {

namespace beast = boost::beast;
namespace http = boost::beast::http;
namespace websocket = boost::beast::websocket;

using HeadParser = http::request_parser<http::empty_body>;

// The header limit. Only heads are read (a body is never read: judgeRequest refuses a
// request that announces one, after the method, so that a POST gets 405).
inline void configureHeadParser(HeadParser& parser, std::size_t max_header_bytes) {
  parser.header_limit(static_cast<std::uint32_t>(max_header_bytes));
  // Not boost::none: Boost 1.74 compares a Content-Length with the optional and counts
  // none as exceeded.
  parser.body_limit(std::numeric_limits<std::uint64_t>::max());
  parser.eager(false);
}

// The status a parser error gets.
inline int statusOfParseError(const boost::system::error_code& ec) {
  if (ec == http::error::header_limit) return 431;
  if (ec == http::error::body_limit || ec == http::error::unexpected_body) return 413;
  return 400;
}

// What judgeRequest needs of a parsed request.
inline RequestHead requestHeadOf(const http::request<http::empty_body>& req) {
  RequestHead head;
  head.method = std::string(req.method_string());
  head.target = std::string(req.target());
  const auto length = req.find(http::field::content_length);
  head.has_body = req.find(http::field::transfer_encoding) != req.end() ||
                  (length != req.end() && length->value() != "0");
  head.is_upgrade = websocket::is_upgrade(req);
  if (auto it = req.find(http::field::host); it != req.end()) head.host = std::string(it->value());
  if (auto it = req.find(http::field::origin); it != req.end()) {
    head.origin = std::string(it->value());
  }
  return head;
}

}  // namespace vistel::server
