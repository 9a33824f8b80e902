// An in-process session over a simulated network with a fake clock (STYLE.md: the pure
// protocol cores run server and clients in one process). One ServerCore, any number of
// ClientSessions, each with its own link model per direction (latency, jitter that
// reorders, loss, duplication) for UDP, and a reliable in-order TCP stream with
// latency. Every client's local clock runs at an offset from the server's, so clock
// synchronisation is measurable. Deterministic for a given seed.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "client/net/client_session.hpp"
#include "server/core/server_core.hpp"

namespace vistel::test {

struct SimLink {
  double latency = 0.010;  // seconds, one way
  double jitter = 0.0;     // extra delay, uniform in [0, jitter] (reorders datagrams)
  double loss = 0.0;       // probability a datagram is lost
  double duplicate = 0.0;  // probability a datagram is delivered twice
};

class SimNetwork {
 public:
  struct Client {
    std::unique_ptr<net::ClientSession> session;
    wire::Endpoint endpoint;
    server::ConnId conn = 0;
    SimLink up;           // client -> server
    SimLink down;         // server -> client
    double clock_offset;  // client local time = server time + clock_offset
    bool connected = false;
    double tcp_up_free = 0.0;  // TCP: next byte cannot arrive before this (in order)
    double tcp_down_free = 0.0;
  };

  explicit SimNetwork(const server::ServerConfig& config, std::uint64_t seed = 1)
      : server_(config, seed), rng_(seed) {}

  server::ServerCore& server() { return server_; }
  double now() const { return now_; }
  std::size_t clientCount() const { return clients_.size(); }
  net::ClientSession& session(std::size_t i) { return *clients_[i].session; }
  Client& client(std::size_t i) { return clients_[i]; }
  double localTime(std::size_t i) const { return now_ + clients_[i].clock_offset; }

  // Adds a client (not yet connected) at endpoint 10.0.0.(i+1):(40000+i).
  std::size_t addClient(net::SessionSettings settings, SimLink up = {}, SimLink down = {},
                        double clock_offset = 0.0,
                        std::shared_ptr<net::AvatarCache> cache = nullptr) {
    Client c;
    const auto i = static_cast<std::uint32_t>(clients_.size());
    c.session = std::make_unique<net::ClientSession>(std::move(settings), std::move(cache));
    c.endpoint = wire::Endpoint::ipv4(0x0A000001u + i, static_cast<std::uint16_t>(40000 + i));
    c.conn = 100 + i;
    c.up = up;
    c.down = down;
    c.clock_offset = clock_offset;
    clients_.push_back(std::move(c));
    return clients_.size() - 1;
  }

  // TCP connection established (instantly) and the session started.
  void connect(std::size_t i) {
    Client& c = clients_[i];
    c.connected = true;
    server_.onConnect(c.conn, now_);
    c.session->start(localTime(i));
    flushAll();
  }

  // The client's TCP connection dies at once (a cable cut, a crash): both ends are told.
  void cut(std::size_t i) {
    Client& c = clients_[i];
    if (!c.connected) return;
    c.connected = false;
    server_.onDisconnect(c.conn, now_);
    c.session->onDisconnected("connection cut", localTime(i));
    flushAll();
  }
  // The client comes back as a new session on a new connection (a restarted program).
  void reconnect(std::size_t i, net::SessionSettings settings) {
    cut(i);
    Client& c = clients_[i];
    c.session = std::make_unique<net::ClientSession>(std::move(settings), nullptr);
    c.conn = next_conn_++;
    c.tcp_up_free = c.tcp_down_free = now_;
    connect(i);
  }
  // Raw traffic from a misbehaving peer (not a session).
  void injectDatagram(std::vector<std::uint8_t> bytes, const wire::Endpoint& from,
                      double delay = 0.0) {
    schedule(now_ + delay,
             [this, bytes = std::move(bytes), from] { server_.onDatagram(bytes, from, now_); });
  }
  void injectConnect(server::ConnId conn) {
    server_.onConnect(conn, now_);
    flushServer();
  }
  void injectStream(server::ConnId conn, std::vector<std::uint8_t> bytes) {
    server_.onStreamBytes(conn, bytes, now_);
    flushServer();
  }
  // Frames the server sent to raw connections, and whether it closed them.
  const std::vector<std::uint8_t>& rawReceived(server::ConnId conn) { return raw_in_[conn]; }
  bool rawClosed(server::ConnId conn) const { return raw_closed_.count(conn) > 0; }
  // A sniffer on the uplinks: from sniff(true) on, a copy of every datagram a client sends
  // (client index, bytes), as it left the client.
  struct Sniffed {
    std::size_t client;
    std::vector<std::uint8_t> bytes;
  };
  void sniff(bool on) { sniffing_ = on; }
  const std::vector<Sniffed>& sniffed() const { return sniffed_; }
  // Datagrams the server sent to endpoints that are not clients.
  std::vector<std::vector<std::uint8_t>>& rawDatagrams(const wire::Endpoint& to) {
    return raw_datagrams_[to.toString()];
  }

  // Advances the clock by `duration` in steps of `step`, delivering what is due and
  // running the server's and every session's timers at each step. `each_step(now)`
  // runs before the timers (send postures there).
  void advance(double duration, double step = 0.001,
               const std::function<void(double)>& each_step = nullptr) {
    const double end = now_ + duration;
    while (now_ < end - 1e-12) {
      now_ = std::min(end, now_ + step);
      deliverDue();
      if (each_step) each_step(now_);
      server_.update(now_);
      for (std::size_t i = 0; i < clients_.size(); ++i) {
        if (clients_[i].connected) clients_[i].session->update(localTime(i));
      }
      flushAll();
    }
  }

  // Counters for the test's own reporting.
  std::uint64_t datagramsLost() const { return lost_; }
  std::uint64_t datagramsSent() const { return sent_; }

 private:
  void schedule(double at, std::function<void()> f) {
    events_.emplace(std::make_pair(at, next_event_++), std::move(f));
  }

  void deliverDue() {
    while (!events_.empty() && events_.begin()->first.first <= now_ + 1e-12) {
      auto f = std::move(events_.begin()->second);
      events_.erase(events_.begin());
      f();
    }
  }

  double uniform() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_); }

  // Sends a datagram over a link: maybe lost, maybe twice, each with its own jitter.
  void sendDatagram(const SimLink& link, std::function<void()> deliver) {
    ++sent_;
    if (uniform() < link.loss) {
      ++lost_;
      return;
    }
    const int copies = uniform() < link.duplicate ? 2 : 1;
    for (int k = 0; k < copies; ++k) {
      schedule(now_ + link.latency + link.jitter * uniform(), deliver);
    }
  }

  Client* clientAt(const wire::Endpoint& e) {
    for (Client& c : clients_) {
      if (c.endpoint == e) return &c;
    }
    return nullptr;
  }
  Client* clientOf(server::ConnId conn) {
    for (Client& c : clients_) {
      if (c.conn == conn) return &c;
    }
    return nullptr;
  }

  void flushAll() {
    flushServer();
    for (std::size_t i = 0; i < clients_.size(); ++i) flushClient(i);
  }

  void flushServer() {
    server::Effects& fx = server_.effects();
    for (server::OutDatagram& d : fx.datagrams) {
      Client* c = clientAt(d.to);
      if (c == nullptr) {
        raw_datagrams_[d.to.toString()].push_back(std::move(d.bytes));
        continue;
      }
      const std::size_t i = static_cast<std::size_t>(c - clients_.data());
      sendDatagram(c->down, [this, i, bytes = d.bytes] {
        if (clients_[i].connected) clients_[i].session->onDatagram(bytes, localTime(i));
      });
    }
    for (server::OutFrame& f : fx.frames) {
      Client* c = clientOf(f.conn);
      if (c == nullptr) {
        auto& in = raw_in_[f.conn];
        in.insert(in.end(), f.bytes.begin(), f.bytes.end());
        continue;
      }
      const std::size_t i = static_cast<std::size_t>(c - clients_.data());
      c->tcp_down_free = std::max(c->tcp_down_free, now_ + c->down.latency);
      schedule(c->tcp_down_free, [this, i, bytes = std::move(f.bytes)] {
        if (clients_[i].connected) clients_[i].session->onStreamBytes(bytes, localTime(i));
      });
    }
    for (server::ConnId conn : fx.closes) {
      Client* c = clientOf(conn);
      if (c == nullptr) {
        raw_closed_[conn] = true;
        continue;
      }
      const std::size_t i = static_cast<std::size_t>(c - clients_.data());
      schedule(std::max(c->tcp_down_free, now_ + c->down.latency), [this, i] {
        if (!clients_[i].connected) return;
        clients_[i].session->onDisconnected("closed by the server", localTime(i));
        clients_[i].connected = false;
      });
    }
    fx.clear();
  }

  void flushClient(std::size_t i) {
    Client& c = clients_[i];
    net::SessionOutbox& out = c.session->outbox();
    if (!out.stream.empty()) {
      c.tcp_up_free = std::max(c.tcp_up_free, now_ + c.up.latency);
      schedule(c.tcp_up_free, [this, conn = c.conn, bytes = std::move(out.stream)] {
        server_.onStreamBytes(conn, bytes, now_);
      });
    }
    for (auto& d : out.datagrams) {
      if (sniffing_) sniffed_.push_back({i, d});
      sendDatagram(c.up, [this, from = c.endpoint, bytes = std::move(d)] {
        server_.onDatagram(bytes, from, now_);
      });
    }
    if (out.close && c.connected) {
      c.connected = false;
      schedule(std::max(c.tcp_up_free, now_ + c.up.latency),
               [this, conn = c.conn] { server_.onDisconnect(conn, now_); });
    }
    out.clear();
  }

  server::ServerCore server_;
  std::vector<Client> clients_;
  double now_ = 0.0;
  std::mt19937_64 rng_;
  std::map<std::pair<double, std::uint64_t>, std::function<void()>> events_;
  std::uint64_t next_event_ = 0;
  server::ConnId next_conn_ = 100000;  // reconnect()'s connections
  bool sniffing_ = false;
  std::vector<Sniffed> sniffed_;
  std::uint64_t lost_ = 0;
  std::uint64_t sent_ = 0;
  std::map<server::ConnId, std::vector<std::uint8_t>> raw_in_;
  std::map<server::ConnId, bool> raw_closed_;
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> raw_datagrams_;
};

}  // namespace vistel::test
