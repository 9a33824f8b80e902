#include "client/net/clock_sync.hpp"

#include <cmath>

namespace vistel::net {

ClockSync::ClockSync(int window) : window_(static_cast<std::size_t>(window < 1 ? 1 : window)) {
  samples_.reserve(window_);
}

void ClockSync::seed(double server_time, double local_time) {
  if (total_samples_ == 0 && std::isfinite(server_time) && std::isfinite(local_time)) {
    offset_ = server_time - local_time;
  }
}

void ClockSync::addSample(double t0, double server_time, double t3) {
  if (!std::isfinite(t0) || !std::isfinite(server_time) || !std::isfinite(t3) || t3 < t0) return;
  const Sample s{server_time - 0.5 * (t0 + t3), t3 - t0};
  if (samples_.size() < window_) {
    samples_.push_back(s);
  } else {
    samples_[next_] = s;
  }
  next_ = (next_ + 1) % window_;
  ++total_samples_;

  // The smallest round trip in the window wins.
  const Sample* best = &samples_[0];
  for (const Sample& c : samples_) {
    if (c.round_trip < best->round_trip) best = &c;
  }
  offset_ = best->offset;
  round_trip_ = best->round_trip;
}

}  // namespace vistel::net
