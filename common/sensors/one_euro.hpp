// The One-Euro filter (Casiez, Roussel & Vogel 2012, "1 Euro Filter: A Simple Speed-based
// Low-pass Filter for Noisy Input in Interactive Systems"): a first-order low-pass whose
// cutoff rises with the signal's speed, so slow motion is smoothed and fast motion is
// followed with little lag. Here for 3-D positions and for rotations (the rotation version
// filters the angular velocity and slerps). For prediction it also keeps a velocity estimate
// (raw differences low-passed at predict_cutoff_hz) and the filter's current lag (an
// exponential smoother with factor a trails a steady ramp by dt (1 - a) / a), so a caller can
// extrapolate value + velocity * (lag + ahead) to undo both the filter lag and the reading's
// age. Allocation-free.
#pragma once

#include <cmath>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/sensors/rotation_utils.hpp"

namespace vistel {

struct OneEuroParams {
  float min_cutoff_hz = 1.0f;      // cutoff at rest
  float beta = 0.0f;               // cutoff increase per unit of speed (Hz per m/s or per rad/s)
  float d_cutoff_hz = 1.0f;        // cutoff of the speed estimate that drives the cutoff
  float predict_cutoff_hz = 5.0f;  // cutoff of the velocity used for prediction
};

inline float oneEuroAlpha(float dt, float cutoff_hz) {
  const float tau = 1.0f / (6.2831853f * cutoff_hz);
  return 1.0f / (1.0f + tau / dt);
}

class OneEuroVec3 {
 public:
  void reset() { initialised_ = false; }
  bool initialised() const { return initialised_; }
  // Adds a sample dt seconds after the previous one (dt <= 0 replaces the value).
  const glm::vec3& update(const glm::vec3& x, float dt, const OneEuroParams& p) {
    if (!initialised_ || !(dt > 0.0f)) {
      if (!initialised_) speed_ = velocity_ = glm::vec3(0.0f);
      value_ = raw_ = x;
      lag_ = 0.0f;
      initialised_ = true;
      return value_;
    }
    speed_ += ((x - value_) / dt - speed_) * oneEuroAlpha(dt, p.d_cutoff_hz);
    velocity_ += ((x - raw_) / dt - velocity_) * oneEuroAlpha(dt, p.predict_cutoff_hz);
    const float a = oneEuroAlpha(dt, p.min_cutoff_hz + p.beta * glm::length(speed_));
    value_ += (x - value_) * a;
    lag_ = dt * (1.0f - a) / a;
    raw_ = x;
    return value_;
  }
  const glm::vec3& value() const { return value_; }
  const glm::vec3& velocity() const { return velocity_; }  // units per second
  float lag() const { return lag_; }                       // seconds

 private:
  glm::vec3 value_{0.0f};
  glm::vec3 raw_{0.0f};
  glm::vec3 speed_{0.0f};
  glm::vec3 velocity_{0.0f};
  float lag_ = 0.0f;
  bool initialised_ = false;
};

class OneEuroQuat {
 public:
  void reset() { initialised_ = false; }
  bool initialised() const { return initialised_; }
  const glm::quat& update(const glm::quat& q_in, float dt, const OneEuroParams& p) {
    const glm::quat q = glm::dot(q_in, value_) < 0.0f ? -q_in : q_in;
    if (!initialised_ || !(dt > 0.0f)) {
      if (!initialised_) speed_ = omega_ = glm::vec3(0.0f);
      value_ = raw_ = q;
      lag_ = 0.0f;
      initialised_ = true;
      return value_;
    }
    // World-frame angular velocities: of the sample relative to the filtered value (drives
    // the cutoff) and relative to the previous sample (for prediction).
    speed_ += (rotationVector(q * glm::conjugate(value_)) / dt - speed_) *
              oneEuroAlpha(dt, p.d_cutoff_hz);
    omega_ += (rotationVector(q * glm::conjugate(raw_)) / dt - omega_) *
              oneEuroAlpha(dt, p.predict_cutoff_hz);
    const float a = oneEuroAlpha(dt, p.min_cutoff_hz + p.beta * glm::length(speed_));
    value_ = glm::normalize(glm::slerp(value_, q, a));
    lag_ = dt * (1.0f - a) / a;
    raw_ = q;
    return value_;
  }
  const glm::quat& value() const { return value_; }
  const glm::vec3& angularVelocity() const { return omega_; }  // rad/s, world frame
  float lag() const { return lag_; }                           // seconds

 private:
  glm::quat value_{1.0f, 0.0f, 0.0f, 0.0f};
  glm::quat raw_{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 speed_{0.0f};
  glm::vec3 omega_{0.0f};
  float lag_ = 0.0f;
  bool initialised_ = false;
};

}  // namespace vistel
