#include "client/net/prop_track.hpp"

#include <algorithm>
#include <cassert>

namespace vistel::net {

PropTrack::PropTrack(int capacity) : entries_(static_cast<std::size_t>(capacity)) {
  assert(capacity >= 2);
}

PropTrack::Push PropTrack::push(std::uint32_t tick, const PropSample& sample) {
  // Refuse a tick already held, and anything older than all when full.
  for (int i = 0; i < count_; ++i) {
    if (entries_[static_cast<std::size_t>(i)].tick == tick) return Push::kDuplicate;
  }
  const int capacity = static_cast<int>(entries_.size());
  if (count_ == capacity) {
    if (sample.time <= entries_[0].sample.time) return Push::kStale;
    std::rotate(entries_.begin(), entries_.begin() + 1, entries_.end());
    --count_;
  }
  // Append, then move back into time order.
  int pos = count_++;
  entries_[static_cast<std::size_t>(pos)] = Entry{tick, sample};
  while (pos > 0 && entries_[static_cast<std::size_t>(pos - 1)].sample.time > sample.time) {
    std::swap(entries_[static_cast<std::size_t>(pos - 1)], entries_[static_cast<std::size_t>(pos)]);
    --pos;
  }
  return Push::kAccepted;
}

bool PropTrack::sample(double t, PropSample& out) const {
  if (count_ == 0) return false;
  const PropSample& first = entries_[0].sample;
  const PropSample& last = entries_[static_cast<std::size_t>(count_ - 1)].sample;
  if (t <= first.time) {
    out = first;
    return true;
  }
  if (t >= last.time) {
    out = last;
    return true;
  }
  // The two states around t (at least two entries here).
  int i = 1;
  while (entries_[static_cast<std::size_t>(i)].sample.time < t) ++i;
  const PropSample& a = entries_[static_cast<std::size_t>(i - 1)].sample;
  const PropSample& b = entries_[static_cast<std::size_t>(i)].sample;
  const double span = b.time - a.time;
  const float alpha = span > 0.0 ? static_cast<float>((t - a.time) / span) : 1.0f;
  out.time = t;
  out.position = glm::mix(a.position, b.position, alpha);
  out.velocity = glm::mix(a.velocity, b.velocity, alpha);
  return true;
}

}  // namespace vistel::net
