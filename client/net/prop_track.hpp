// The recent states of one prop as snapshots deliver them (DESIGN.md §6: clients
// interpolate props like postures). Snapshots arrive out of order, duplicated or not at
// all; the track keeps the newest `capacity` distinct ticks in time order and answers
// "where is the prop at time t" by interpolating the two states around t linearly (a
// ball's path between two 1/60 s ticks is nearly straight; bounces are kept as they
// happened at the ticks). Before the first state or after the last one it holds the
// nearest one (no extrapolation).
//
// Memory: `capacity` states allocated at construction; nothing afterwards.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace vistel::net {

struct PropSample {
  double time = 0.0;         // server clock, seconds
  glm::vec3 position{0.0f};  // centre, room space, metres
  glm::vec3 velocity{0.0f};  // m/s
};

class PropTrack {
 public:
  explicit PropTrack(int capacity = 32);

  enum class Push { kAccepted, kDuplicate, kStale };
  // A state of tick `tick` at server time `sample.time`.
  Push push(std::uint32_t tick, const PropSample& sample);

  // The state at server time t (out.time = t clamped to the held span). False when empty.
  bool sample(double t, PropSample& out) const;

  int size() const { return count_; }
  bool empty() const { return count_ == 0; }
  // The newest state held (undefined when empty).
  const PropSample& newest() const { return entries_[static_cast<std::size_t>(count_ - 1)].sample; }
  void clear() { count_ = 0; }

 private:
  struct Entry {
    std::uint32_t tick = 0;
    PropSample sample;
  };
  std::vector<Entry> entries_;  // first count_ used, ascending time
  int count_ = 0;
};

}  // namespace vistel::net
