// StationFilter: the sensor-space filter of one 6-DOF station (DESIGN.md §5), run by the
// posture solver before the solve and evaluated at every frame time.
//
// Estimator: a Kalman filter (Kalman 1960) per station, position and orientation alike, with
// a white-jerk (constant acceleration) or white-acceleration (constant velocity) motion
// model, per axis (Bar-Shalom, Li & Kirubarajan 2001, §6.3); the orientation through the
// rotation vector of the error between a reading and the prediction (world frame,
// re-based on every reading). The reading's variance R is the tracker's noise model (the
// sensors config's figures: RMS of the 3-D position error and of the rotation angle, split
// evenly over three axes); the process density is set by one corner: the steady-state
// continuous filter of an n-fold integrator is an n-th order Butterworth low-pass with
// corner (q / R_c)^(1/2n) (Kalman & Bucy 1961), R_c = R * (reading interval), so
// q = R_c (2 pi cutoff_hz)^(2n). The gains then depend on the corner and the reading interval
// alone; the noise figures set the covariances' scale (the start-up prior). The corner rises
// with the station's own estimated speed (low-passed) by beta, Hz per m/s or per rad/s, up to
// max_cutoff_hz. At a corner f and reading interval T the filter still passes about 2 f T of
// each reading's noise (its gain on the newest reading): that, not the corner, sets the
// floor under the jitter.
//
// Output: the estimate extrapolated by its own motion model to the asked time less the delay
// (delay_s plus delay_intervals reading intervals: the reading's age, latency and, with a
// shared update rate, the other stations' turns), so
// time keeps running between readings. A new reading changes that trajectory; the change
// (the old output minus the new trajectory, in value, velocity and acceleration, at the
// reading) is folded in along the minimum-jerk path: the quintic that starts at that
// difference and reaches zero with zero velocity and acceleration after ease_intervals
// reading intervals (no step in position, velocity or acceleration at a reading, and the
// least integrated squared jerk that allows; a blend between the old and the new
// trajectories would also carry the old one's growing extrapolation error, and over two
// intervals left a 120 Hz output about as shaky as over half of one). Only the corrected
// part is delayed.
//
// Times are seconds on the frame clock; positions metres; rotations world frame (tracker
// space). Readings not newer than the last are ignored; no input fails. Allocation-free;
// every call O(1).
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/sensors/rotation_utils.hpp"

namespace vistel {

struct StationFilterParams {
  // The tracker's noise model (a FASTRAK's by default; the sensors config's [tracker]).
  float position_noise_m = 0.0008f;     // RMS of the 3-D position error of one reading
  float orientation_noise_deg = 0.15f;  // RMS rotation angle of one reading
  // Corners, Hz: where the body's motion sinks below the noise.
  float position_cutoff_hz = 4.0f;
  float orientation_cutoff_hz = 4.0f;
  // The corner rises with the station's own estimated speed (as One Euro's cutoff does):
  // Hz per m/s and per rad/s. A still trunk is smoothed hard, a walking one followed.
  float position_beta = 0.0f;
  float orientation_beta = 0.0f;
  float speed_cutoff_hz = 1.0f;       // the speed is low-passed at this corner
  float max_cutoff_hz = 8.0f;         // the corners rise no higher (a noisy speed feeds back)
  bool constant_acceleration = true;  // white jerk (else white acceleration)
  // Fold each correction in over this many reading intervals. Two: a 120 Hz output of 30 Hz
  // readings no longer shakes at every reading (bench_posture, CMU 131_01 with noise: jitter
  // 13.3x -> 2.5x of the clip's at 0.5 intervals -> 2), for about 6 ms more lag there and a
  // little more error and 30 fps jitter on the gesture clips (bow 5.3x -> 5.8x).
  double ease_intervals = 2.0;

  double max_extrapolate_s = 0.2;  // never extrapolate further past the last reading
  // The output is the estimate this long before the asked time (lag spent on less
  // extrapolation: a shorter prediction amplifies the readings' noise and the motion's own
  // high frequencies less). 0: the estimate at the asked time. Plus delay_intervals of the
  // station's own reading interval (its running mean), so that the output can be interpolated
  // between readings, not extrapolated past the newest, at whatever rate the station reports.
  double delay_s = 0.0;
  double delay_intervals = 0.0;
  // Where on its segment the posture solver filters a station's position: 0 at the sensor,
  // 1 at the joint the segment turns about (the elbow for a wrist sensor), between: between.
  float pivot = 1.0f;
};

// A scalar-per-axis Kalman filter on a 3-vector: value, velocity, acceleration (all three
// axes share one covariance: the noise is isotropic).
class Kalman3 {
 public:
  void init(const glm::dvec3& x, double var_x, double var_v, double var_a) {
    x_ = x;
    v_ = a_ = glm::dvec3(0.0);
    p_ = glm::dmat3(0.0);
    p_[0][0] = var_x;
    p_[1][1] = var_v;
    p_[2][2] = var_a;
  }
  // Advances by dt with process density q (white jerk, or white acceleration with the
  // acceleration held at zero when !ca).
  void predict(double dt, double q, bool ca) {
    if (!(dt > 0.0)) return;
    x_ += v_ * dt + a_ * (0.5 * dt * dt);
    v_ += a_ * dt;
    glm::dmat3 f(1.0);  // column-major: f[col][row]
    f[1][0] = dt;
    f[2][0] = 0.5 * dt * dt;
    f[2][1] = dt;
    p_ = f * p_ * glm::transpose(f);
    const double d2 = dt * dt, d3 = d2 * dt, d4 = d3 * dt, d5 = d4 * dt;
    if (!ca) {
      add(0, 0, q * d3 / 3.0);
      add(0, 1, q * d2 / 2.0);
      add(1, 1, q * dt);
      for (int i = 0; i < 3; ++i) p_[2][i] = p_[i][2] = 0.0;
      a_ = glm::dvec3(0.0);
      return;
    }
    add(0, 0, q * d5 / 20.0);
    add(0, 1, q * d4 / 8.0);
    add(0, 2, q * d3 / 6.0);
    add(1, 1, q * d3 / 3.0);
    add(1, 2, q * d2 / 2.0);
    add(2, 2, q * dt);
  }
  // Measures the value: innovation e (reading minus predicted value), variance r.
  void correct(const glm::dvec3& e, double r) {
    const double s = p_[0][0] + r;
    const glm::dvec3 k(p_[0][0] / s, p_[0][1] / s, p_[0][2] / s);
    x_ += e * k.x;
    v_ += e * k.y;
    a_ += e * k.z;
    glm::dmat3 p = p_;
    for (int c = 0; c < 3; ++c)
      for (int row = 0; row < 3; ++row) p[c][row] -= k[row] * p_[c][0];
    p_ = 0.5 * (p + glm::transpose(p));
  }
  void setValue(const glm::dvec3& x) { x_ = x; }
  const glm::dvec3& value() const { return x_; }
  const glm::dvec3& velocity() const { return v_; }
  const glm::dvec3& acceleration() const { return a_; }

 private:
  void add(int i, int j, double v) {
    p_[i][j] += v;
    if (i != j) p_[j][i] += v;
  }
  glm::dvec3 x_{0.0}, v_{0.0}, a_{0.0};
  glm::dmat3 p_{0.0};
};

class StationFilter {
 public:
  void reset() { initialised_ = false; }
  bool initialised() const { return initialised_; }

  // A reading measured at t_meas and first seen at frame time t_now >= t_meas. A reading not
  // newer than the last one is ignored. The first reading (or the first after reset()) is
  // taken as it is, at rest.
  void update(const glm::vec3& p, const glm::quat& q_in, double t_meas, double t_now_in,
              const StationFilterParams& params) {
    delay_ = params.delay_s + (initialised_ ? params.delay_intervals * interval_ : 0.0);
    const double t_now = t_now_in - delay_;
    const double sp = params.position_noise_m / std::sqrt(3.0);
    const double sr =
        glm::radians(static_cast<double>(params.orientation_noise_deg)) / std::sqrt(3.0);
    const double rp = std::max(sp * sp, 1e-14);
    const double rr = std::max(sr * sr, 1e-14);
    const double cp = 6.283185307179586 *
                      std::min<double>(params.position_cutoff_hz + params.position_beta * speed_p_,
                                       std::max(params.max_cutoff_hz, params.position_cutoff_hz));
    const double cr =
        6.283185307179586 *
        std::min<double>(params.orientation_cutoff_hz + params.orientation_beta * speed_r_,
                         std::max(params.max_cutoff_hz, params.orientation_cutoff_hz));
    if (!initialised_) {
      // Starting at rest, about as sure of the velocity and acceleration as the corner lets
      // the filter be in steady state (a wide prior would make the first second shake).
      pos_.init(glm::dvec3(p), rp, rp * cp * cp, rp * cp * cp * cp * cp);
      rot_.init(glm::dvec3(0.0), rr, rr * cr * cr, rr * cr * cr * cr * cr);
      q0_ = q_in;
      t0_ = t_meas;
      interval_ = 0.0;
      speed_p_ = speed_r_ = 0.0;
      now_ = snapshot();
      corr_x_ = corr_r_ = Correction{};
      settling_ = kSettlingReadings;
      blend_t0_ = t_now;

      initialised_ = true;
      return;
    }
    const double dt = t_meas - t0_;
    if (!(dt > 0.0)) return;
    const Poly before = blendedAt(t_now, params);
    if (settling_ > 0) --settling_;
    // The reading interval (for the process density and the easing): a running mean that one
    // odd gap does not throw.
    interval_ =
        interval_ > 0.0 ? interval_ + 0.2 * (std::min(dt, 4.0 * interval_) - interval_) : dt;
    const bool ca = params.constant_acceleration;
    const double n2 = ca ? 6.0 : 4.0;
    const double wp = std::pow(cp, n2);
    const double wr = std::pow(cr, n2);
    pos_.predict(dt, rp * interval_ * wp, ca);
    pos_.correct(glm::dvec3(p) - pos_.value(), rp);
    rot_.predict(dt, rr * interval_ * wr, ca);
    const glm::quat q_pred = glm::normalize(fromRotationVector(glm::vec3(rot_.value())) * q0_);
    const glm::quat q = glm::dot(q_in, q_pred) < 0.0f ? -q_in : q_in;
    rot_.correct(glm::dvec3(rotationVector(q * glm::conjugate(q_pred))), rr);
    q0_ = glm::normalize(fromRotationVector(glm::vec3(rot_.value())) * q0_);
    rot_.setValue(glm::dvec3(0.0));
    t0_ = t_meas;
    // The speeds that raise the corners, low-passed at speed_cutoff_hz (a noisy speed would
    // feed back into the corner).
    const double a_s = 1.0 - std::exp(-6.283185307179586 * params.speed_cutoff_hz * dt);
    speed_p_ += (glm::length(pos_.velocity()) - speed_p_) * a_s;
    speed_r_ += (glm::length(rot_.velocity()) - speed_r_) * a_s;
    now_ = snapshot();
    // The correction still to fold in: the output so far minus the new trajectory.
    const Poly cur = at(now_, t_now, params);
    corr_x_ = {before.x - cur.x, before.v - cur.v, before.a - cur.a};
    corr_r_ = {glm::dvec3(rotationVector(normalizeSafe(before.q * glm::inverse(cur.q)))),
               before.w - cur.w, before.alpha - cur.alpha};
    blend_t0_ = t_now;
  }

  // The eased estimate at time t (at or after the last update's t_now).
  void evaluate(double t, const StationFilterParams& params, glm::vec3& p, glm::quat& q) const {
    const Poly o = blendedAt(t - delay_, params);
    p = glm::vec3(o.x);
    q = o.q;
  }

  // The estimate at the last reading's time, neither extrapolated nor eased.
  void current(glm::vec3& p, glm::quat& q) const {
    p = glm::vec3(now_.x);
    q = now_.q;
  }

  glm::vec3 velocity() const { return glm::vec3(now_.v); }         // m/s
  glm::vec3 angularVelocity() const { return glm::vec3(now_.w); }  // rad/s, world frame
  double interval() const { return interval_; }                    // s between readings

 private:
  // A trajectory anchored at time t: value and its first two derivatives.
  struct Poly {
    double t = 0.0;
    glm::dvec3 x{0.0}, v{0.0}, a{0.0};
    glm::quat q{1.0f, 0.0f, 0.0f, 0.0f};
    glm::dvec3 w{0.0}, alpha{0.0};
  };

  // A correction being folded in: value, first and second derivative at its start.
  struct Correction {
    glm::dvec3 d0{0.0}, d1{0.0}, d2{0.0};
  };

  // The quintic that starts at c (value, slope, curvature) and reaches zero with zero slope
  // and curvature at tau = span, at tau in [0, span]: value, slope and curvature.
  static void quintic(const Correction& c, double tau, double span, glm::dvec3& x, glm::dvec3& v,
                      glm::dvec3& a) {
    const double u = std::clamp(tau / span, 0.0, 1.0);
    const double u2 = u * u, u3 = u2 * u, u4 = u3 * u, u5 = u4 * u;
    const double h0 = 1.0 - 10.0 * u3 + 15.0 * u4 - 6.0 * u5;
    const double h0d = -30.0 * u2 * (1.0 - u) * (1.0 - u) / span;
    const double h0dd = -60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (span * span);
    const double h1 = (u - 6.0 * u3 + 8.0 * u4 - 3.0 * u5) * span;
    const double h1d = 1.0 - 18.0 * u2 + 32.0 * u3 - 15.0 * u4;
    const double h1dd = (-36.0 * u + 96.0 * u2 - 60.0 * u3) / span;
    const double h2 = 0.5 * (u2 - 3.0 * u3 + 3.0 * u4 - u5) * span * span;
    const double h2d = 0.5 * (2.0 * u - 9.0 * u2 + 12.0 * u3 - 5.0 * u4) * span;
    const double h2dd = 1.0 - 9.0 * u + 18.0 * u2 - 10.0 * u3;
    x = c.d0 * h0 + c.d1 * h1 + c.d2 * h2;
    v = c.d0 * h0d + c.d1 * h1d + c.d2 * h2d;
    a = c.d0 * h0dd + c.d1 * h1dd + c.d2 * h2dd;
  }

  // While the filter settles after a (re)start at rest, its corrections are the state
  // catching up with a moving station, not noise: they are folded in over at most half an
  // interval (a longer span would overlap them into an overshoot).
  static constexpr int kSettlingReadings = 8;
  double easeSpan(const StationFilterParams& params) const {
    const double e = settling_ > 0 ? std::min(params.ease_intervals, 0.5) : params.ease_intervals;
    return e * interval_;
  }

  Poly snapshot() const {
    Poly s;
    s.t = t0_;
    s.x = pos_.value();
    s.v = pos_.velocity();
    s.a = pos_.acceleration();
    s.q = q0_;
    s.w = rot_.velocity();
    s.alpha = rot_.acceleration();
    return s;
  }

  Poly at(const Poly& s, double t, const StationFilterParams& params) const {
    // (Back along the trajectory, by at most the delay, when a delay puts t before the
    // reading.)
    const double tau = std::clamp(t - s.t, -delay_, params.max_extrapolate_s);
    Poly o;
    o.t = t;
    o.x = s.x + s.v * tau + s.a * (0.5 * tau * tau);
    o.v = s.v + s.a * tau;
    o.a = s.a;
    o.q = glm::normalize(fromRotationVector(glm::vec3(s.w * tau + s.alpha * (0.5 * tau * tau))) *
                         s.q);
    o.w = s.w + s.alpha * tau;
    o.alpha = s.alpha;
    return o;
  }

  // The eased output at t, as a trajectory anchored at t: the filter's trajectory plus what
  // is left of the last correction.
  Poly blendedAt(double t, const StationFilterParams& params) const {
    Poly o = at(now_, t, params);
    const double span = easeSpan(params);
    const double tau = t - blend_t0_;
    if (!(span > 0.0) || tau >= span) return o;
    glm::dvec3 x, v, a;
    quintic(corr_x_, tau, span, x, v, a);
    o.x += x;
    o.v += v;
    o.a += a;
    quintic(corr_r_, tau, span, x, v, a);
    o.q = glm::normalize(fromRotationVector(glm::vec3(x)) * o.q);
    o.w += v;
    o.alpha += a;
    return o;
  }

  Kalman3 pos_;
  Kalman3 rot_;  // rotation vector relative to q0_ (zero after every reading)
  glm::quat q0_{1.0f, 0.0f, 0.0f, 0.0f};
  double t0_ = 0.0;        // time of the last reading
  double interval_ = 0.0;  // running mean of the reading interval
  double delay_ = 0.0;     // the output's delay (s), set at each reading
  double blend_t0_ = 0.0;
  double speed_p_ = 0.0, speed_r_ = 0.0;  // low-passed speeds, m/s and rad/s
  Poly now_;
  Correction corr_x_, corr_r_;  // position; rotation (rotation vector, world frame)
  int settling_ = 0;            // readings left before the full easing span

  bool initialised_ = false;
};

}  // namespace vistel
