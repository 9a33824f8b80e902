#include "server/web/web_limits.hpp"

#include <algorithm>

namespace vistel::server {

WebLimits::WebLimits(const WebConfig& config) : config_(config) {}

WebLimits::Address& WebLimits::entry(const std::string& address, double now) {
  auto it = addresses_.find(address);
  if (it == addresses_.end()) {
    if (addresses_.size() >= kMaxTracked) prune(now);
    it = addresses_
             .emplace(address, Address{0,
                                       TokenBucket(config_.request_rate_hz,
                                                   static_cast<double>(config_.request_burst), now),
                                       now})
             .first;
  }
  it->second.last_seen = now;
  return it->second;
}

void WebLimits::prune(double now) {
  // An address with nothing open whose bucket would be full again is as good as new.
  const double refill_s =
      static_cast<double>(config_.request_burst) / std::max(1e-9, config_.request_rate_hz);
  for (auto it = addresses_.begin(); it != addresses_.end();) {
    if (it->second.open == 0 && now - it->second.last_seen >= refill_s) {
      it = addresses_.erase(it);
    } else {
      ++it;
    }
  }
}

std::string_view WebLimits::admit(const std::string& address, double now) {
  std::string_view reason;
  if (open_ >= config_.max_connections) {
    reason = "connection limit";
  } else {
    Address& a = entry(address, now);
    if (a.open >= config_.max_connections_per_address) {
      reason = "connections per address";
    } else {
      ++a.open;
      ++open_;
      return {};
    }
  }
  auto it = refusals_.find(reason);
  if (it == refusals_.end()) it = refusals_.emplace(std::string(reason), 0).first;
  ++it->second;
  return reason;
}

void WebLimits::release(const std::string& address) {
  auto it = addresses_.find(address);
  if (it == addresses_.end() || it->second.open == 0) return;
  --it->second.open;
  --open_;
}

bool WebLimits::allowRequest(const std::string& address, double now) {
  if (entry(address, now).bucket.take(now)) return true;
  auto it = refusals_.find(std::string_view("request rate"));
  if (it == refusals_.end()) it = refusals_.emplace("request rate", 0).first;
  ++it->second;
  return false;
}

int WebLimits::openFrom(const std::string& address) const {
  auto it = addresses_.find(address);
  return it == addresses_.end() ? 0 : it->second.open;
}

}  // namespace vistel::server
