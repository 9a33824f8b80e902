// A jitter buffer for one remote member's postures (DESIGN.md §6: clients interpolate
// with a small jitter buffer). Postures arrive out of order, duplicated or not at all;
// the buffer keeps the newest `capacity` distinct ones in capture-time order and
// answers "the posture at time t" by interpolating the two around t. The caller plays
// back a little behind the newest arrival (SessionSettings::interpolation_delay_s) so
// that late packets still fit in.
//
// Memory: capacity postures sized at the first push; no allocation afterwards as long
// as the joint count stays the same.
#pragma once

#include <cstdint>
#include <vector>

#include "common/anim/posture.hpp"

namespace vistel::net {

class JitterBuffer {
 public:
  explicit JitterBuffer(int capacity = 32);

  enum class Push {
    kAccepted,   // new posture, now buffered
    kDuplicate,  // this sequence number is already buffered
    kStale,      // older than everything kept while the buffer is full
  };
  // Inserts a posture (its time: capture time, server clock) under its sequence number.
  Push push(std::uint16_t sequence, const Posture& posture);

  // The posture at server time t: spherical blend of the two buffered postures around t,
  // the oldest one before the first, the newest after the last (held, not
  // extrapolated). False when empty. out.time = t clamped to the buffered span.
  bool sample(double t, Posture& out) const;

  int size() const { return count_; }
  bool empty() const { return count_ == 0; }
  double oldestTime() const;
  double newestTime() const;
  void clear() { count_ = 0; }

 private:
  struct Entry {
    std::uint16_t sequence = 0;
    Posture posture;
  };
  std::vector<Entry> entries_;  // first count_ used, ascending capture time
  int count_ = 0;
};

}  // namespace vistel::net
