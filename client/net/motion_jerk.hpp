// The jerk of a stream of joint positions sampled at increasing, possibly uneven times (what
// a viewer drew of a remote member, or what that member sent): at every sample from the
// fourth on, the third divided difference of the last four samples times 6 (the third
// derivative of the cubic through them; for even spacing dt it is the third difference over
// dt^3), its length averaged over the points; the mean over samples, m/s^3. Issue 21's
// jitter measure (common/sensors/posture_metrics.hpp) for streams with their own clocks.
//
// Samples closer than kMinSpacing seconds to the previous one are skipped (a frame drawn
// twice at one time adds nothing). No allocation once the point count is set.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace vistel::net {

class MotionJerk {
 public:
  static constexpr double kMinSpacing = 1e-4;  // seconds

  // A sample at time t (seconds; after the previous one) of `points` (metres; the same count
  // every call: a different count starts the stream again). Returns the sample's jerk
  // (m/s^3), or -1 while the window fills or when the sample is skipped.
  double add(double t, std::span<const glm::vec3> points);
  // Adds a value measured elsewhere to the sums (totals over streams).
  void addValue(double jerk) {
    sum_ += jerk;
    ++count_;
  }
  // Adds another stream's sums (for totals over members).
  void merge(const MotionJerk& other);

  std::uint64_t count() const { return count_; }
  double mean() const { return count_ > 0 ? sum_ / static_cast<double>(count_) : 0.0; }

 private:
  std::array<double, 4> t_{};
  std::array<std::vector<glm::vec3>, 4> p_;  // ring: slot (next_ + k) % 4 is the k-th oldest
  int next_ = 0;
  int filled_ = 0;
  double sum_ = 0.0;
  std::uint64_t count_ = 0;
};

}  // namespace vistel::net
