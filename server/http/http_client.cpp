// The client side of http_message: connect, write the request, read until the server
// closes, parse. One strand per exchange; a timer closes the socket at the deadline.
#include "server/http/http_client.hpp"

#include <array>
#include <chrono>
#include <memory>

namespace vistel::server {
namespace {

using tcp = asio::ip::tcp;

struct Exchange : std::enable_shared_from_this<Exchange> {
  Exchange(asio::io_context& io, HttpClientRequest r, HttpClientCallback d)
      : strand(asio::make_strand(io)),
        socket(strand),
        deadline(strand),
        request(std::move(r)),
        done(std::move(d)) {}

  void start(tcp::endpoint where) {
    deadline.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(request.timeout_s)));
    deadline.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec) return;
      self->finish(fail("{} {} to {}:{}: timed out after {} s", self->request.method,
                        self->request.target, self->request.host, self->request.port,
                        self->request.timeout_s));
    });
    socket.async_connect(where, [self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec) return self->finish(self->failure("connect", ec));
      self->out = serializeRequest(self->request.method, self->request.target,
                                   fmtHost(self->request), self->request.body);
      asio::async_write(self->socket, asio::buffer(self->out),
                        [self](const boost::system::error_code& wec, std::size_t) {
                          if (wec) return self->finish(self->failure("write", wec));
                          self->read();
                        });
    });
  }

  static std::string fmtHost(const HttpClientRequest& r) {
    return fmt::format("{}:{}", r.host, r.port);
  }

  void read() {
    socket.async_read_some(asio::buffer(chunk), [self = shared_from_this()](
                                                    const boost::system::error_code& ec,
                                                    std::size_t n) {
      if (self->finished) return;
      self->in.append(self->chunk.data(), n);
      if (self->in.size() > self->request.max_response_bytes) {
        return self->finish(fail("{} {}: response longer than {} bytes", self->request.method,
                                 self->request.target, self->request.max_response_bytes));
      }
      if (ec == asio::error::eof) {
        auto response = parseResponse(self->in, self->request.method == "HEAD");
        if (!response) {
          return self->finish(withContext(
              fmt::format("{} {}", self->request.method, self->request.target), response.error()));
        }
        return self->finish(std::move(*response));
      }
      if (ec) return self->finish(self->failure("read", ec));
      self->read();
    });
  }

  Error failure(const char* step, const boost::system::error_code& ec) const {
    return fail("{} {} to {}:{}: {} failed: {}", request.method, request.target, request.host,
                request.port, step, ec.message());
  }

  void finish(Result<HttpClientResponse> result) {
    if (finished) return;
    finished = true;
    boost::system::error_code ignored;
    socket.close(ignored);
    deadline.cancel();
    if (done) done(std::move(result));
  }

  asio::strand<asio::io_context::executor_type> strand;
  tcp::socket socket;
  asio::steady_timer deadline;
  HttpClientRequest request;
  HttpClientCallback done;
  std::string out;
  std::string in;
  std::array<char, 4096> chunk{};
  bool finished = false;
};

}  // namespace

void httpRequest(asio::io_context& io, HttpClientRequest request, HttpClientCallback done) {
  std::string host = request.host == "localhost" ? "127.0.0.1" : request.host;
  boost::system::error_code ec;
  asio::ip::address address = asio::ip::make_address(host, ec);
  auto exchange = std::make_shared<Exchange>(io, std::move(request), std::move(done));
  if (ec) {
    Error error = fail("{} {}: host '{}' is not an IP address", exchange->request.method,
                       exchange->request.target, exchange->request.host);
    asio::post(exchange->strand, [exchange, error] { exchange->finish(error); });
    return;
  }
  tcp::endpoint where(address, exchange->request.port);
  asio::post(exchange->strand, [exchange, where] { exchange->start(where); });
}

}  // namespace vistel::server
