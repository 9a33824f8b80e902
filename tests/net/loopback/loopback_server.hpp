// A session server on loopback for tests of the client's real network side (NetDriver):
// the pure ServerCore behind a small single-threaded Asio shell of its own (TCP acceptor
// and UDP socket on one port of 127.0.0.1, a 5 ms timer), so the tests depend only on the
// protocol core, not on the production shell. Everything runs on the harness's own I/O
// thread; inspect() runs a function there and waits for its result.
//
// stop() ends it the way a crash or kill does (sockets closed, nobody told);
// stop(/*graceful=*/true) first tells every connection SHUTTING_DOWN. sever() closes every
// TCP connection without telling the core, as a network cut the server has not noticed
// yet: its members stay until they time out.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <future>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "client/net/asio.hpp"
#include "server/core/server_core.hpp"

namespace vistel::test {

namespace asio = boost::asio;

class LoopbackServer {
 public:
  // Listens on 127.0.0.1:port (0: a free port, the same number for TCP and UDP).
  explicit LoopbackServer(const server::ServerConfig& config, std::uint16_t port = 0)
      : core_(config, 0), acceptor_(io_), udp_(io_), timer_(io_) {
    open(port);
    accept();
    receive();
    tick();
    thread_ = std::thread([this] { io_.run(); });
  }
  ~LoopbackServer() { stop(); }
  LoopbackServer(const LoopbackServer&) = delete;
  LoopbackServer& operator=(const LoopbackServer&) = delete;

  std::uint16_t port() const { return port_; }

  void stop(bool graceful = false) {
    if (!thread_.joinable()) return;
    asio::post(io_, [this, graceful] {
      if (graceful) {
        core_.shutdown(now());
        flush();
        for (auto& [id, c] : conns_) writeAllNow(*c);
      }
      closeAll();
      io_.stop();
    });
    thread_.join();
  }

  // Runs f(core) on the server's thread and returns what it returns.
  template <typename F>
  auto inspect(F&& f) {
    using R = decltype(f(std::declval<const server::ServerCore&>()));
    std::promise<R> done;
    asio::post(io_, [&] { done.set_value(f(static_cast<const server::ServerCore&>(core_))); });
    return done.get_future().get();
  }

  // Closes every TCP connection without telling the core (an unnoticed network cut).
  void sever() {
    inspect([this](const server::ServerCore&) {
      for (auto& [id, c] : conns_) {
        c->severed = true;
        boost::system::error_code ignored;
        c->socket.close(ignored);
      }
      return 0;
    });
  }

 private:
  struct Conn {
    explicit Conn(asio::ip::tcp::socket s) : socket(std::move(s)) {}
    asio::ip::tcp::socket socket;
    std::vector<std::uint8_t> buffer = std::vector<std::uint8_t>(16u << 10);
    std::deque<std::vector<std::uint8_t>> queue;
    bool writing = false;
    bool close_after_write = false;
    bool severed = false;
  };

  static double now() {
    static const auto kStart = std::chrono::steady_clock::now();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - kStart).count();
  }

  // Binds both sockets to one port: a given one, or a free TCP port that UDP can share.
  void open(std::uint16_t port) {
    const auto loopback = asio::ip::address_v4::loopback();
    for (int attempt = 0; attempt < 20; ++attempt) {
      boost::system::error_code ec;
      acceptor_ = asio::ip::tcp::acceptor(io_);
      acceptor_.open(asio::ip::tcp::v4(), ec);
      acceptor_.set_option(asio::socket_base::reuse_address(true), ec);
      acceptor_.bind({loopback, port}, ec);
      if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
      if (ec) continue;
      port_ = acceptor_.local_endpoint().port();
      udp_ = asio::ip::udp::socket(io_);
      udp_.open(asio::ip::udp::v4(), ec);
      if (!ec) udp_.bind({loopback, port_}, ec);
      if (!ec) return;
    }
    throw std::runtime_error("loopback server: cannot bind port " + std::to_string(port));
  }

  void accept() {
    acceptor_.async_accept(
        [this](const boost::system::error_code& ec, asio::ip::tcp::socket socket) {
          if (ec) return;  // closed
          const server::ConnId id = next_conn_++;
          boost::system::error_code ignored;
          socket.set_option(asio::ip::tcp::no_delay(true), ignored);
          auto c = std::make_shared<Conn>(std::move(socket));
          conns_[id] = c;
          core_.onConnect(id, now());
          read(id, c);
          flush();
          accept();
        });
  }

  void read(server::ConnId id, std::shared_ptr<Conn> c) {
    c->socket.async_read_some(asio::buffer(c->buffer),
                              [this, id, c](const boost::system::error_code& ec, std::size_t n) {
                                if (c->severed) return;
                                if (ec) {
                                  if (conns_.erase(id) > 0) core_.onDisconnect(id, now());
                                  flush();
                                  return;
                                }
                                core_.onStreamBytes(id, std::span(c->buffer.data(), n), now());
                                flush();
                                read(id, c);
                              });
  }

  void receive() {
    udp_.async_receive_from(
        asio::buffer(datagram_), from_, [this](const boost::system::error_code& ec, std::size_t n) {
          if (ec == asio::error::operation_aborted || !udp_.is_open()) return;
          if (!ec) {
            core_.onDatagram(std::span(datagram_.data(), n), toWire(from_), now());
            flush();
          }
          receive();
        });
  }

  void tick() {
    timer_.expires_after(std::chrono::milliseconds(5));
    timer_.async_wait([this](const boost::system::error_code& ec) {
      if (ec) return;
      core_.update(now());
      flush();
      tick();
    });
  }

  // Carries out the core's effects.
  void flush() {
    server::Effects& fx = core_.effects();
    for (const server::OutDatagram& d : fx.datagrams) {
      boost::system::error_code ignored;
      udp_.send_to(asio::buffer(d.bytes), toAsio(d.to), 0, ignored);
    }
    for (server::OutFrame& f : fx.frames) {
      auto it = conns_.find(f.conn);
      if (it == conns_.end()) continue;
      it->second->queue.push_back(std::move(f.bytes));
      write(f.conn, it->second);
    }
    for (server::ConnId id : fx.closes) {
      auto it = conns_.find(id);
      if (it == conns_.end()) continue;
      it->second->close_after_write = true;
      write(id, it->second);
    }
    fx.clear();
  }

  void write(server::ConnId id, std::shared_ptr<Conn> c) {
    if (c->writing || c->severed) return;
    if (c->queue.empty()) {
      if (c->close_after_write) {
        boost::system::error_code ignored;
        c->socket.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
        c->socket.close(ignored);
        conns_.erase(id);
      }
      return;
    }
    c->writing = true;
    asio::async_write(c->socket, asio::buffer(c->queue.front()),
                      [this, id, c](const boost::system::error_code& ec, std::size_t) {
                        c->writing = false;
                        if (ec) return;  // the read side reports the loss
                        c->queue.pop_front();
                        write(id, c);
                      });
  }

  // Graceful stop: what is queued goes out now, blocking (small: error replies).
  static void writeAllNow(Conn& c) {
    // (A write in flight owns the front buffer: it is not sent twice.)
    for (std::size_t i = c.writing ? 1 : 0; i < c.queue.size(); ++i) {
      boost::system::error_code ignored;
      asio::write(c.socket, asio::buffer(c.queue[i]), ignored);
    }
  }

  void closeAll() {
    boost::system::error_code ignored;
    timer_.cancel();
    acceptor_.close(ignored);
    udp_.close(ignored);
    for (auto& [id, c] : conns_) {
      c->severed = true;
      c->socket.close(ignored);
    }
    conns_.clear();
  }

  static wire::Endpoint toWire(const asio::ip::udp::endpoint& e) {
    return wire::Endpoint::ipv4(e.address().to_v4().to_uint(), e.port());
  }
  static asio::ip::udp::endpoint toAsio(const wire::Endpoint& w) {
    return {asio::ip::address_v4(w.ipv4Address()), w.port};
  }

  server::ServerCore core_;
  asio::io_context io_;
  asio::ip::tcp::acceptor acceptor_;
  asio::ip::udp::socket udp_;
  asio::steady_timer timer_;
  std::uint16_t port_ = 0;
  std::map<server::ConnId, std::shared_ptr<Conn>> conns_;
  server::ConnId next_conn_ = 1;
  std::vector<std::uint8_t> datagram_ = std::vector<std::uint8_t>(65536);
  asio::ip::udp::endpoint from_;
  std::thread thread_;
};

}  // namespace vistel::test
