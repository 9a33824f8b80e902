#include "client/net/motion_jerk.hpp"

#include <algorithm>

namespace vistel::net {

double MotionJerk::add(double t, std::span<const glm::vec3> points) {
  if (points.empty()) return -1.0;
  const int newest = (next_ + 3) % 4;
  if (filled_ > 0) {
    if (p_[static_cast<std::size_t>(newest)].size() != points.size()) {
      filled_ = 0;  // another skeleton: another stream
    } else if (!(t - t_[static_cast<std::size_t>(newest)] >= kMinSpacing)) {
      return -1.0;
    }
  }
  auto& slot = p_[static_cast<std::size_t>(next_)];
  slot.assign(points.begin(), points.end());
  t_[static_cast<std::size_t>(next_)] = t;
  next_ = (next_ + 1) % 4;
  filled_ = std::min(filled_ + 1, 4);
  if (filled_ < 4) return -1.0;
  // Oldest to newest: slots next_, next_ + 1, ...
  std::array<double, 4> ts;
  std::array<const std::vector<glm::vec3>*, 4> ps;
  for (int k = 0; k < 4; ++k) {
    const auto s = static_cast<std::size_t>((next_ + k) % 4);
    ts[static_cast<std::size_t>(k)] = t_[s];
    ps[static_cast<std::size_t>(k)] = &p_[s];
  }
  // Newton's divided differences, per point: f[t0..t3] = ((f[t1..t3] - f[t0..t2]) / (t3 - t0)).
  const double d01 = ts[1] - ts[0], d12 = ts[2] - ts[1], d23 = ts[3] - ts[2];
  const double d02 = ts[2] - ts[0], d13 = ts[3] - ts[1], d03 = ts[3] - ts[0];
  double total = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const glm::dvec3 f0((*ps[0])[i]), f1((*ps[1])[i]), f2((*ps[2])[i]), f3((*ps[3])[i]);
    const glm::dvec3 a = (f1 - f0) / d01, b = (f2 - f1) / d12, c = (f3 - f2) / d23;
    const glm::dvec3 ab = (b - a) / d02, bc = (c - b) / d13;
    total += glm::length(6.0 * (bc - ab) / d03);
  }
  const double jerk = total / static_cast<double>(points.size());
  addValue(jerk);
  return jerk;
}

void MotionJerk::merge(const MotionJerk& other) {
  sum_ += other.sum_;
  count_ += other.count_;
}

}  // namespace vistel::net
