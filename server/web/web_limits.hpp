// Admission and request rate of the spectator web server, per source address: at most
// max_connections open in all and max_connections_per_address from one address (loopback
// included: a browser opens a handful), and a token bucket of request_rate_hz requests
// per second (request_burst at once) per address, which also covers WebSocket upgrades.
// Refusals are counted by reason. The table of addresses is bounded: past kMaxTracked,
// addresses without open connections whose bucket has refilled are forgotten.
//
// Pure and single-threaded (the server holds a mutex around it); time is the caller's
// clock in seconds.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <unordered_map>

#include "server/core/rate_limit.hpp"
#include "server/web/web_config.hpp"

namespace vistel::server {

class WebLimits {
 public:
  static constexpr std::size_t kMaxTracked = 4096;

  explicit WebLimits(const WebConfig& config);

  // A new connection: empty when admitted (counted until release()), else the reason
  // ("connection limit" or "connections per address"), counted.
  std::string_view admit(const std::string& address, double now);
  void release(const std::string& address);
  // One request (or upgrade) from `address`: false when over its rate ("request rate",
  // counted); the caller answers 429.
  bool allowRequest(const std::string& address, double now);

  int open() const { return open_; }
  int openFrom(const std::string& address) const;
  std::size_t tracked() const { return addresses_.size(); }
  const std::map<std::string, std::uint64_t, std::less<>>& refusals() const { return refusals_; }

 private:
  struct Address {
    int open = 0;
    TokenBucket bucket;
    double last_seen = 0.0;
  };
  Address& entry(const std::string& address, double now);
  void prune(double now);

  WebConfig config_;
  int open_ = 0;
  std::unordered_map<std::string, Address> addresses_;
  std::map<std::string, std::uint64_t, std::less<>> refusals_;
};

}  // namespace vistel::server
