// RigSimulator: a SensorSource that derives what the four trackers (six with foot_trackers)
// and two gloves would report from a moving body (a mocap clip sampled over time), so the
// solver can be scored against the clip's true joints (DESIGN.md §5).
//
// Each station is a sensor mounted on its segment (SensorMount, fixed at the calibration
// posture = the body at t = 0). Tracker space is model space. Timing: ticks at rate_hz; with
// shared_rate the worn stations take turns (a FASTRAK's 120 Hz shared by 4 receivers gives
// each 30 Hz; 6 stations at 120 Hz get 20 Hz each), else all sample every tick. Stations
// not worn (the feet without foot_trackers) are never valid. A reading arriving at tick time t
// measured the body at t - latency. Noise: Gaussian, isotropic, given as the RMS of the 3-D
// position error and of the rotation angle; deterministic for a seed (own generator). Dropouts:
// scheduled intervals and/or random ones (Poisson, rate per station) during which the station
// reports nothing (valid = false). Gloves report a synthetic pattern for the fingers and, when
// wrist_from_motion, the body's own wrist flexion/deviation (hand_model.hpp).
//
// poll() never waits: every call produces the next tick's frame, kEnd after hold + duration.
// Allocation-free per tick once the sampler has warmed up.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/sensors/body_roles.hpp"
#include "common/sensors/glove_synth.hpp"
#include "common/sensors/hand_model.hpp"
#include "common/sensors/random.hpp"
#include "common/sensors/sensor_mount.hpp"
#include "common/sensors/sensor_source.hpp"

namespace vistel {

struct StationDropout {
  BodySite site = BodySite::kHead;
  double start_s = 0.0;
  double duration_s = 0.0;
};

struct SimOptions {
  double hold_s = 0.0;  // the body holds its t = 0 posture this long before moving (a
                        // participant standing still for calibration); body time = t - hold_s
  double rate_hz = 120.0;
  bool shared_rate = true;
  double latency_s = 0.004;
  float position_noise_m = 0.0008f;     // RMS of the 3-D position error
  float orientation_noise_deg = 0.15f;  // RMS rotation angle
  std::uint64_t seed = 1;
  std::vector<StationDropout> dropouts;
  double random_dropout_rate_hz = 0.0;  // expected dropouts per second per station
  double random_dropout_s = 0.25;       // length of each random dropout
  std::array<SensorMount, kBodySiteCount> mounts = defaultSensorMounts();
  // Also a tracker on each foot (six stations, same noise model); the skeleton must have
  // foot joints.
  bool foot_trackers = false;
  GlovePattern glove = GlovePattern::kNeutral;
  double glove_period_s = 2.0;
  bool glove_wrist_from_motion = true;
  float glove_noise_deg = 0.0f;  // RMS per sensor
};

// The same options without noise (and without latency): for exactness tests.
SimOptions noiselessSimOptions();

// Writes the body's posture at time t (seconds) into out; must be deterministic.
using PostureSampler = std::function<void(double t, Posture& out)>;

class RigSimulator final : public SensorSource {
 public:
  // Fails when options are out of range (rate <= 0, negative noise or latency) or the
  // roles do not fit the skeleton.
  static Result<std::unique_ptr<RigSimulator>> create(Skeleton body, const JointRoles& roles,
                                                      PostureSampler sampler, double duration_s,
                                                      SimOptions options);

  PollResult poll(double timeout_s, SensorFrame& frame) override;
  std::string describe() const override;

  const Skeleton& body() const { return body_; }
  const JointRoles& roles() const { return roles_; }
  const SimOptions& options() const { return options_; }
  // The body at t = 0, where the mounts were fixed: the calibration posture.
  const Posture& calibrationPosture() const { return calibration_; }
  double duration() const { return duration_; }
  double tickInterval() const { return 1.0 / options_.rate_hz; }
  // The body's own time (the clip's) at a frame time: t - hold_s, not below 0.
  double bodyTime(double t) const { return std::max(0.0, t - options_.hold_s); }
  // The true posture at frame time t.
  void truth(double t, Posture& out) const { sampler_(bodyTime(t), out); }
  // Where each sensor sits on its segment (segment -1: the skeleton lacks it).
  const std::array<AttachedSensor, kBodySiteCount>& sensors() const { return sensors_; }
  // True when the site is in a (scheduled or random) dropout at time t.
  bool droppedOut(BodySite site, double t) const;

 private:
  RigSimulator() : rng_(1) {}
  void sampleBody(double t);

  Skeleton body_;
  JointRoles roles_{};
  PostureSampler sampler_;
  double duration_ = 0.0;
  SimOptions options_;
  Posture calibration_;
  std::array<AttachedSensor, kBodySiteCount> sensors_{};
  std::array<int, kBodySiteCount> worn_{};  // the worn sites, in order
  int worn_count_ = 0;
  std::array<WristModel, 2> wrists_{};
  std::vector<StationDropout> schedule_;  // scheduled + random dropouts
  SimRandom rng_;
  std::int64_t tick_ = 0;
  std::uint64_t sequence_ = 0;
  SensorFrame state_;
  Posture scratch_;               // body at the sample time
  std::vector<glm::mat4> model_;  // (njoint) its joint transforms
};

}  // namespace vistel
