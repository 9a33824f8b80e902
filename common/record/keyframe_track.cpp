#include "common/record/keyframe_track.hpp"

#include <algorithm>
#include <cmath>

namespace vistel::record {
namespace {

// Linear interpolation of the value type (the interpolation glTF's LINEAR applies).
glm::vec3 interpolate(const glm::vec3& a, const glm::vec3& b, float u) { return glm::mix(a, b, u); }
glm::quat interpolate(const glm::quat& a, const glm::quat& b, float u) {
  return glm::slerp(a, b, u);
}

float distance(const glm::vec3& a, const glm::vec3& b) { return glm::length(a - b); }
float distance(const glm::quat& a, const glm::quat& b) { return rotationAngle(a, b); }

// Keeps a rotation in the hemisphere of the previous one (the same rotation either way).
glm::vec3 aligned(const glm::vec3& value, const glm::vec3&) { return value; }
glm::quat aligned(const glm::quat& value, const glm::quat& previous) {
  return glm::dot(value, previous) < 0.0f ? -value : value;
}

}  // namespace

float rotationAngle(const glm::quat& a, const glm::quat& b) {
  // |a - b| = 2 sin(theta / 4) for unit quaternions in one hemisphere: stable at small angles.
  const glm::quat bb = glm::dot(a, b) < 0.0f ? -b : b;
  const glm::vec4 d(a.x - bb.x, a.y - bb.y, a.z - bb.z, a.w - bb.w);
  const float half_chord = std::min(1.0f, 0.5f * glm::length(d));
  return 4.0f * std::asin(half_chord);
}

template <typename V>
void KeyframeTrack<V>::add(double t, const V& value) {
  const bool any = !times_.empty() || !pending_t_.empty();
  const double last_t = !pending_t_.empty() ? pending_t_.back() : any ? times_.back() : 0.0;
  if (any && !(t > last_t)) return;  // not after the previous sample
  ++samples_;
  const V v = !pending_v_.empty() ? aligned(value, pending_v_.back())
              : !values_.empty()  ? aligned(value, values_.back())
                                  : value;
  // A new segment starts with a key.
  if (!open_) {
    commit(t, v);
    open_ = true;
    return;
  }
  // A repeated value: only the newest of a run equal to the key needs keeping (the error of
  // a segment from the key grows with the distance from it, so it is the one to check).
  if (pending_equal_ && v == values_.back() && !pending_t_.empty()) {
    pending_t_.back() = t;
    return;
  }
  // The segment from the last key to this sample still fits every sample in between.
  if (pending_t_.empty() || (pending_t_.size() < kMaxPending && fits(t, v))) {
    pending_equal_ = pending_equal_ && v == values_.back();
    pending_t_.push_back(t);
    pending_v_.push_back(v);
    return;
  }
  // It does not: the previous sample becomes a key and the segment restarts from it.
  commit(pending_t_.back(), pending_v_.back());
  pending_t_.push_back(t);
  pending_v_.push_back(v);
  pending_equal_ = v == values_.back();
}

template <typename V>
void KeyframeTrack<V>::cut() {
  if (!pending_t_.empty()) commit(pending_t_.back(), pending_v_.back());
  open_ = false;
}

template <typename V>
bool KeyframeTrack<V>::constant() const {
  return std::all_of(values_.begin(), values_.end(),
                     [this](const V& v) { return v == values_.front(); });
}

template <typename V>
bool KeyframeTrack<V>::fits(double t, const V& value) const {
  const double t0 = times_.back();
  const V& v0 = values_.back();
  if (pending_equal_ && value == v0) return true;  // a repeated value: nothing to check
  const double span = t - t0;
  for (std::size_t i = 0; i < pending_t_.size(); ++i) {
    const auto u = static_cast<float>((pending_t_[i] - t0) / span);
    if (distance(interpolate(v0, value, u), pending_v_[i]) > tolerance_) return false;
  }
  return true;
}

template <typename V>
void KeyframeTrack<V>::commit(double t, const V& value) {
  times_.push_back(t);
  values_.push_back(value);
  pending_t_.clear();
  pending_v_.clear();
  pending_equal_ = true;
}

template class KeyframeTrack<glm::vec3>;
template class KeyframeTrack<glm::quat>;

}  // namespace vistel::record
