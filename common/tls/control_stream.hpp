// The control channel's byte stream: plain TCP, or TLS over it (Asio's OpenSSL layer).
// One type for both so the server shell and the client driver read, write and close the
// same way whichever it is. Not thread-safe: use it on one strand, as a socket.
#pragma once

#include <utility>

#include <boost/asio.hpp>
#include <boost/asio/ssl.hpp>

#include <memory>
#include <optional>

namespace vistel::tls {

namespace asio = boost::asio;
using Tcp = asio::ip::tcp;
using TlsStream = asio::ssl::stream<Tcp::socket>;

class ControlStream {
 public:
  // Plain TCP on this socket.
  explicit ControlStream(Tcp::socket socket) : plain_(std::move(socket)) {}
  // TLS over this socket with this context (which must outlive the stream).
  ControlStream(Tcp::socket socket, asio::ssl::context& context)
      : tls_(std::make_unique<TlsStream>(std::move(socket), context)) {}

  bool isTls() const { return tls_ != nullptr; }
  Tcp::socket& socket() { return tls_ ? tls_->next_layer() : *plain_; }
  // The TLS stream (isTls() only): for SNI and verification settings before the handshake.
  TlsStream& tlsStream() { return *tls_; }

  // The TLS handshake (client or server side); a plain stream completes at once.
  template <typename Handler>
  void asyncHandshake(asio::ssl::stream_base::handshake_type type, Handler&& handler) {
    if (tls_) {
      tls_->async_handshake(type, std::forward<Handler>(handler));
    } else {
      asio::post(plain_->get_executor(), [h = std::forward<Handler>(handler)]() mutable {
        h(boost::system::error_code{});
      });
    }
  }
  template <typename Buffers, typename Handler>
  void asyncReadSome(const Buffers& buffers, Handler&& handler) {
    if (tls_) {
      tls_->async_read_some(buffers, std::forward<Handler>(handler));
    } else {
      plain_->async_read_some(buffers, std::forward<Handler>(handler));
    }
  }
  // All of the buffers (asio::async_write).
  template <typename Buffers, typename Handler>
  void asyncWrite(const Buffers& buffers, Handler&& handler) {
    if (tls_) {
      asio::async_write(*tls_, buffers, std::forward<Handler>(handler));
    } else {
      asio::async_write(*plain_, buffers, std::forward<Handler>(handler));
    }
  }
  // Shuts the TCP connection down both ways and closes it (no TLS close_notify: the
  // control protocol ends on its own messages). Errors are ignored.
  void close() {
    boost::system::error_code ignored;
    socket().shutdown(Tcp::socket::shutdown_both, ignored);
    socket().close(ignored);
  }

 private:
  std::optional<Tcp::socket> plain_;
  std::unique_ptr<TlsStream> tls_;
};

}  // namespace vistel::tls
