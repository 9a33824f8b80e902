#include "client/net/join_backoff.hpp"

#include <algorithm>
#include <cmath>

namespace vistel::net {

JoinBackoff::JoinBackoff(const BackoffSettings& settings, std::uint64_t seed)
    : settings_(settings), rng_(seed) {}

double JoinBackoff::nextDelay(double hint_s) {
  if (attempts_ >= settings_.max_attempts) return -1.0;
  const double first = std::max(settings_.base_s, std::isfinite(hint_s) ? hint_s : 0.0);
  const double cap = std::min(settings_.max_s, first * std::ldexp(1.0, std::min(attempts_, 30)));
  ++attempts_;
  std::uniform_real_distribution<double> jitter(0.5, 1.0);
  return cap * jitter(rng_);
}

}  // namespace vistel::net
