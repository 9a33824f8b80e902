#include "client/net/jitter_buffer.hpp"

#include <algorithm>
#include <cassert>

namespace vistel::net {

JitterBuffer::JitterBuffer(int capacity) : entries_(static_cast<std::size_t>(capacity)) {
  assert(capacity >= 2);
}

JitterBuffer::Push JitterBuffer::push(std::uint16_t sequence, const Posture& posture) {
  // Refuse what is already here, and what is older than everything when full.
  for (int i = 0; i < count_; ++i) {
    if (entries_[static_cast<std::size_t>(i)].sequence == sequence) return Push::kDuplicate;
  }
  const int capacity = static_cast<int>(entries_.size());
  if (count_ == capacity) {
    if (posture.time <= entries_[0].posture.time) return Push::kStale;
    // Drop the oldest: rotate it to the end, where the new entry is written.
    std::rotate(entries_.begin(), entries_.begin() + 1, entries_.end());
    --count_;
  }

  // Place by capture time: write into the first free slot, then move it back into order.
  int pos = count_;
  Entry& slot = entries_[static_cast<std::size_t>(pos)];
  slot.sequence = sequence;
  slot.posture.time = posture.time;
  slot.posture.root_translation = posture.root_translation;
  slot.posture.rotations.assign(posture.rotations.begin(), posture.rotations.end());
  slot.posture.translations.clear();
  ++count_;
  while (pos > 0 && entries_[static_cast<std::size_t>(pos - 1)].posture.time > posture.time) {
    std::swap(entries_[static_cast<std::size_t>(pos - 1)], entries_[static_cast<std::size_t>(pos)]);
    --pos;
  }
  return Push::kAccepted;
}

bool JitterBuffer::sample(double t, Posture& out) const {
  if (count_ == 0) return false;
  const auto copy = [&out](const Posture& p) {
    out.time = p.time;
    out.root_translation = p.root_translation;
    out.rotations.assign(p.rotations.begin(), p.rotations.end());
    out.translations.clear();
  };
  const Posture& first = entries_[0].posture;
  const Posture& last = entries_[static_cast<std::size_t>(count_ - 1)].posture;
  if (t <= first.time) {
    copy(first);
    return true;
  }
  if (t >= last.time) {
    copy(last);
    return true;
  }
  // The pair around t (times ascend; at least two entries here).
  int i = 1;
  while (entries_[static_cast<std::size_t>(i)].posture.time < t) ++i;
  const Posture& a = entries_[static_cast<std::size_t>(i - 1)].posture;
  const Posture& b = entries_[static_cast<std::size_t>(i)].posture;
  if (a.rotations.size() != b.rotations.size()) {
    copy(b);
    return true;
  }
  const double span = b.time - a.time;
  const float alpha = span > 0.0 ? static_cast<float>((t - a.time) / span) : 1.0f;
  blendPostures(a, b, alpha, out);
  out.translations.clear();
  return true;
}

double JitterBuffer::oldestTime() const { return count_ > 0 ? entries_[0].posture.time : 0.0; }

double JitterBuffer::newestTime() const {
  return count_ > 0 ? entries_[static_cast<std::size_t>(count_ - 1)].posture.time : 0.0;
}

}  // namespace vistel::net
