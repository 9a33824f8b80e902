// A jitter buffer for one remote member's postures (DESIGN.md §6: clients interpolate
// with a small jitter buffer). Postures arrive out of order, duplicated or not at all;
// the buffer keeps the newest `capacity` distinct ones in capture-time order and
// answers "the posture at time t" by interpolating the two around t along a cubic through
// their neighbours (a blend of the two alone kinks the motion at every received posture,
// which a viewer sees as shake: remote_jitter.hpp measures it). The caller plays
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

  // The posture at server time t: cubic Hermite interpolation of the two buffered postures
  // around t (Catmull-Rom tangents from their neighbours; quaternion components, normalised),
  // the oldest one before the first, the newest after the last (held, not
  // extrapolated). False when empty. out.time = t clamped to the buffered span.
  bool sample(double t, Posture& out) const;

  // What a sample at t shows (playback_stats.hpp counts them).
  enum class Shown {
    kNone,          // nothing buffered
    kInterpolated,  // t within the buffered span: blended from the two around t
    kHeld,          // no data for t: before the oldest (the oldest shown), or past the newest
                    // by more than the extrapolation limit (the pose at the limit, frozen)
    kExtrapolated,  // past the newest by at most the limit: continued along the last two
  };
  // sample() with extrapolation: past the newest posture by up to max_extrapolation_s
  // (seconds, >= 0; 0 = hold as sample() does), the motion from the second newest to the
  // newest continues (rotations along their great arcs, translations along lines); further
  // past, the pose reached at the limit is held (no jump back). Needs two postures at
  // least 0.1 ms apart to extrapolate, else it holds. `shown_capture_time` (optional)
  // receives the capture time (server clock) of what is shown: t when interpolated, the
  // oldest's or the newest's time otherwise (extrapolation invents no newer data), so
  // serverNow - it is the shown posture's age. No allocation once `out` has the joints.
  Shown sampleShown(double t, double max_extrapolation_s, Posture& out,
                    double* shown_capture_time = nullptr) const;
  // What sampleShown would return, without computing the posture (cheap: no blending).
  Shown classify(double t, double max_extrapolation_s, double* shown_capture_time = nullptr) const;

  int size() const { return count_; }
  bool empty() const { return count_ == 0; }
  double oldestTime() const;
  double newestTime() const;
  // The oldest buffered posture captured after t (server clock), or null.
  const Posture* firstAfter(double t) const;
  void clear() { count_ = 0; }

 private:
  struct Entry {
    std::uint16_t sequence = 0;
    Posture posture;
  };
  static constexpr double kMinExtrapolationSpan = 1e-4;  // seconds between the last two
  std::vector<Entry> entries_;  // first count_ used, ascending capture time
  int count_ = 0;
};

}  // namespace vistel::net
