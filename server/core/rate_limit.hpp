// A token bucket: `rate` tokens per second up to `burst`, so a peer may send bursts of
// `burst` messages and `rate` per second sustained. Time is the caller's clock (seconds);
// a clock that goes backwards adds nothing.
#pragma once

#include <algorithm>

namespace vistel::server {

class TokenBucket {
 public:
  TokenBucket() = default;
  TokenBucket(double rate, double burst, double now)
      : rate_(rate), burst_(burst), tokens_(burst), last_(now) {}

  // Refills for the time since the last call, then takes `cost` tokens if there are that
  // many (true) or takes none (false).
  bool take(double now, double cost = 1.0) {
    if (now > last_) {
      tokens_ = std::min(burst_, tokens_ + (now - last_) * rate_);
      last_ = now;
    }
    if (tokens_ < cost) return false;
    tokens_ -= cost;
    return true;
  }

  double tokens() const { return tokens_; }

 private:
  double rate_ = 0.0;
  double burst_ = 0.0;
  double tokens_ = 0.0;
  double last_ = 0.0;
};

}  // namespace vistel::server
