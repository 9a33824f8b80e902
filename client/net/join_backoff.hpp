// When to try joining again after the server refused a join for a transient reason
// (ErrorReply.retry_after_s > 0: SERVER_FULL, an upload that timed out), so that a crowd
// refused at once does not come back at once (proto/SESSION.md §4 "Joining again").
//
// Attempt k (from 0) waits a delay drawn uniformly from [cap_k / 2, cap_k], where
// cap_k = min(max_s, max(base_s, hint) * 2^k) and hint is the server's retry_after_s:
// exponential growth, never below half the server's hint, and jitter that spreads a
// crowd over half of each window. Deterministic for a given seed (tests); no clock.
#pragma once

#include <cstdint>
#include <random>

namespace vistel::net {

struct BackoffSettings {
  double base_s = 0.5;   // the first window when the server gives no hint
  double max_s = 15.0;   // no window is longer
  int max_attempts = 8;  // refusals in a row before giving up (0: never retry)
};

class JoinBackoff {
 public:
  JoinBackoff(const BackoffSettings& settings, std::uint64_t seed);

  // After a refusal with the server's hint (seconds, > 0): the delay before the next
  // attempt, or a negative value when max_attempts refusals in a row have been met.
  double nextDelay(double hint_s);
  // A join succeeded: the next refusal starts from the first window again.
  void reset() { attempts_ = 0; }
  // Refusals in a row so far.
  int attempts() const { return attempts_; }

 private:
  BackoffSettings settings_;
  std::mt19937_64 rng_;
  int attempts_ = 0;
};

}  // namespace vistel::net
