// A sampled animation track reduced to keyframes as the samples arrive (greedy online
// reduction): a sample is dropped while the straight segment (lerp for vectors, slerp for
// rotations) from the last key to the newest sample passes within the tolerance of every
// sample in between; otherwise the previous sample becomes a key. Played back with
// glTF's LINEAR interpolation, the keys reproduce every sample within the tolerance.
//
// Units: time in seconds (strictly increasing; a sample not after the previous one is
// ignored); vectors in metres (or unitless for scale) with a Euclidean tolerance;
// rotations as unit quaternions with an angular tolerance in radians (consecutive keys are
// kept in the same hemisphere so that interpolation takes the short arc).
//
// Memory: the keys, plus at most kMaxPending samples since the last key (a key is forced
// when the window is full; a run repeating the key's value exactly counts as one sample).
// Cost per sample: O(window); O(1) while the value repeats exactly (a member at rest, a
// held posture), however long.
#pragma once

#include <cstddef>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace vistel::record {

template <typename V>
class KeyframeTrack {
 public:
  static constexpr std::size_t kMaxPending = 96;

  explicit KeyframeTrack(float tolerance = 0.0f) : tolerance_(tolerance) {}

  // A sample at time t (seconds, after the previous sample).
  void add(double t, const V& value);
  // A discontinuity: the last sample becomes a key and the next one starts afresh (a
  // member left and joined again; nothing is interpolated across the gap's start).
  void cut();
  // Makes the last sample a key (call before reading the keys). Adding afterwards is fine.
  void finish() { cut(); }

  const std::vector<double>& times() const { return times_; }
  const std::vector<V>& values() const { return values_; }
  std::size_t samples() const { return samples_; }
  // True when every key holds exactly the same value (a constant channel; no keys: true).
  bool constant() const;

 private:
  bool fits(double t, const V& value) const;
  void commit(double t, const V& value);

  float tolerance_;
  std::vector<double> times_;  // keys
  std::vector<V> values_;
  std::vector<double> pending_t_;  // samples after the last key (oldest first)
  std::vector<V> pending_v_;
  bool pending_equal_ = true;  // every pending value equals the last key's exactly
  bool open_ = false;          // a segment is open (the next sample may extend it)
  std::size_t samples_ = 0;
};

using Vec3Track = KeyframeTrack<glm::vec3>;
using QuatTrack = KeyframeTrack<glm::quat>;

// The angle (radians, in [0, pi]) between two unit rotations.
float rotationAngle(const glm::quat& a, const glm::quat& b);

}  // namespace vistel::record
