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
  return sampleShown(t, 0.0, out) != Shown::kNone;
}

JitterBuffer::Shown JitterBuffer::classify(double t, double max_extrapolation_s,
                                           double* shown_capture_time) const {
  double shown = t;
  Shown kind = Shown::kInterpolated;
  if (count_ == 0) {
    kind = Shown::kNone;
    shown = 0.0;
  } else if (const double first = entries_[0].posture.time; t < first) {
    kind = Shown::kHeld;
    shown = first;
  } else if (const double last = newestTime(); t > last) {
    // Past the newest: extrapolated within the limit from two distinct postures.
    const bool can_extrapolate =
        count_ >= 2 && max_extrapolation_s > 0.0 &&
        last - entries_[static_cast<std::size_t>(count_ - 2)].posture.time >= kMinExtrapolationSpan;
    kind = can_extrapolate && t - last <= max_extrapolation_s ? Shown::kExtrapolated : Shown::kHeld;
    shown = last;
  }
  if (shown_capture_time != nullptr) *shown_capture_time = shown;
  return kind;
}

JitterBuffer::Shown JitterBuffer::sampleShown(double t, double max_extrapolation_s, Posture& out,
                                              double* shown_capture_time) const {
  const Shown kind = classify(t, max_extrapolation_s, shown_capture_time);
  if (kind == Shown::kNone) return kind;
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
    return kind;
  }
  if (t >= last.time) {
    // Past the newest: continue the last two postures' motion up to the limit, then hold
    // the pose reached there (a held pose without extrapolation is the newest itself).
    const Posture& before =
        count_ >= 2 ? entries_[static_cast<std::size_t>(count_ - 2)].posture : last;
    const double span = last.time - before.time;
    const double ahead = std::min(t - last.time, std::max(max_extrapolation_s, 0.0));
    if (count_ < 2 || span < kMinExtrapolationSpan || ahead <= 0.0 ||
        before.rotations.size() != last.rotations.size()) {
      copy(last);
      return kind;
    }
    blendPostures(before, last, static_cast<float>(1.0 + ahead / span), out);
    out.translations.clear();
    return kind;
  }
  // The pair around t (times ascend; at least two entries here).
  int i = 1;
  while (entries_[static_cast<std::size_t>(i)].posture.time < t) ++i;
  const Posture& a = entries_[static_cast<std::size_t>(i - 1)].posture;
  const Posture& b = entries_[static_cast<std::size_t>(i)].posture;
  if (a.rotations.size() != b.rotations.size()) {
    copy(b);
    return kind;
  }
  const double span = b.time - a.time;
  const float alpha = span > 0.0 ? static_cast<float>((t - a.time) / span) : 1.0f;
  blendPostures(a, b, alpha, out);
  out.translations.clear();
  return kind;
}

double JitterBuffer::oldestTime() const { return count_ > 0 ? entries_[0].posture.time : 0.0; }

double JitterBuffer::newestTime() const {
  return count_ > 0 ? entries_[static_cast<std::size_t>(count_ - 1)].posture.time : 0.0;
}

}  // namespace vistel::net
