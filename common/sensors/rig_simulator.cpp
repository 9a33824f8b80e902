#include "common/sensors/rig_simulator.hpp"

#include <cmath>

#include "common/sensors/rotation_utils.hpp"

namespace vistel {

SimOptions noiselessSimOptions() {
  SimOptions o;
  o.latency_s = 0.0;
  o.position_noise_m = 0.0f;
  o.orientation_noise_deg = 0.0f;
  return o;
}

Result<std::unique_ptr<RigSimulator>> RigSimulator::create(Skeleton body, const JointRoles& roles,
                                                           PostureSampler sampler,
                                                           double duration_s, SimOptions options) {
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 10000.0)) {
    return fail("simulator: rate {} Hz out of range (0, 10000]", options.rate_hz);
  }
  if (!(options.latency_s >= 0.0) || !(options.position_noise_m >= 0.0f) ||
      !(options.orientation_noise_deg >= 0.0f) || !(options.glove_noise_deg >= 0.0f)) {
    return fail("simulator: latency and noise must be non-negative");
  }
  if (!(duration_s >= 0.0) || !(options.hold_s >= 0.0)) {
    return fail("simulator: negative duration or hold");
  }
  for (int r = 0; r < kRoleCount; ++r) {
    if (roles.joint[r] >= body.jointCount()) return fail("simulator: roles do not fit skeleton");
  }
  if (!sampler) return fail("simulator: no posture sampler");
  std::unique_ptr<RigSimulator> sim(new RigSimulator());
  sim->body_ = std::move(body);
  sim->roles_ = roles;
  sim->sampler_ = std::move(sampler);
  sim->duration_ = duration_s;
  sim->options_ = std::move(options);
  sim->rng_ = SimRandom(sim->options_.seed);
  sim->model_.resize(static_cast<std::size_t>(sim->body_.jointCount()));

  // The calibration posture fixes the mounts and the wrist convention.
  sim->sampler_(0.0, sim->calibration_);
  if (sim->calibration_.rotations.size() != sim->model_.size()) {
    return fail("simulator: sampler gave {} joint rotations for a {}-joint skeleton",
                sim->calibration_.rotations.size(), sim->model_.size());
  }
  poseSkeleton(sim->body_, sim->calibration_, sim->model_);
  sim->sensors_ = attachSensors(roles, sim->model_, sim->options_.mounts);
  for (int s = 0; s < kBodySiteCount; ++s) {
    if (isFootSite(static_cast<BodySite>(s)) && !sim->options_.foot_trackers) continue;
    if (sim->sensors_[static_cast<std::size_t>(s)].segment < 0) {
      return fail("simulator: the skeleton has no segment for the {} sensor",
                  bodySiteName(static_cast<BodySite>(s)));
    }
    sim->worn_[static_cast<std::size_t>(sim->worn_count_++)] = s;
  }
  std::vector<glm::vec3> positions(sim->model_.size());
  for (std::size_t j = 0; j < positions.size(); ++j) positions[j] = glm::vec3(sim->model_[j][3]);
  const BodyFrame frame = bodyFrameAt(roles, positions);
  for (int side = 0; side < 2; ++side) {
    const int f = roles[forearmRole(side)];
    const int h = roles[handRole(side)];
    const glm::quat fw = glm::normalize(glm::quat_cast(glm::mat3(sim->model_[f])));
    const glm::quat hw = glm::normalize(glm::quat_cast(glm::mat3(sim->model_[h])));
    const glm::vec3 axis = glm::inverse(fw) * (positions[h] - positions[f]);
    sim->wrists_[side] = makeWristModel(side, frame, fw, hw, axis);
  }

  // Dropout schedule: the given intervals plus random ones drawn once from the seed.
  sim->schedule_ = sim->options_.dropouts;
  if (sim->options_.random_dropout_rate_hz > 0.0) {
    SimRandom drops(sim->options_.seed ^ 0xD50F0C7ull);
    for (int k = 0; k < sim->worn_count_; ++k) {
      const int s = sim->worn_[static_cast<std::size_t>(k)];
      double t = 0.0;
      for (;;) {
        t += -std::log(1.0 - drops.uniform()) / sim->options_.random_dropout_rate_hz;
        if (t >= duration_s + sim->options_.hold_s) break;
        sim->schedule_.push_back({static_cast<BodySite>(s), t, sim->options_.random_dropout_s});
      }
    }
  }
  sim->scratch_ = sim->calibration_;
  return sim;
}

bool RigSimulator::droppedOut(BodySite site, double t) const {
  for (const StationDropout& d : schedule_) {
    if (d.site == site && t >= d.start_s && t < d.start_s + d.duration_s) return true;
  }
  return false;
}

void RigSimulator::sampleBody(double t) {
  sampler_(bodyTime(t), scratch_);
  poseSkeleton(body_, scratch_, model_);
}

PollResult RigSimulator::poll(double /*timeout_s*/, SensorFrame& frame) {
  const double t = static_cast<double>(tick_) / options_.rate_hz;
  if (t > duration_ + options_.hold_s + 1e-9) return PollResult::end("simulated clip finished");
  const double t_measured = std::max(0.0, t - options_.latency_s);
  sampleBody(t_measured);

  // Which stations measure on this tick.
  const int first = options_.shared_rate ? static_cast<int>(tick_ % worn_count_) : 0;
  const int last = options_.shared_rate ? first + 1 : worn_count_;
  const float sigma_p = options_.position_noise_m / std::sqrt(3.0f);
  const float sigma_r = glm::radians(options_.orientation_noise_deg) / std::sqrt(3.0f);
  for (int k = first; k < last; ++k) {
    const int s = worn_[static_cast<std::size_t>(k)];
    StationReading& r = state_.stations[s];
    const BodySite site = static_cast<BodySite>(s);
    if (droppedOut(site, t_measured)) {
      r.valid = false;
      continue;
    }
    glm::vec3 p;
    glm::quat q;
    sensorPose(sensors_[s], model_, p, q);
    if (sigma_p > 0.0f) {
      p += glm::vec3(static_cast<float>(rng_.gaussian()), static_cast<float>(rng_.gaussian()),
                     static_cast<float>(rng_.gaussian())) *
           sigma_p;
    }
    if (sigma_r > 0.0f) {
      const glm::vec3 e(static_cast<float>(rng_.gaussian()), static_cast<float>(rng_.gaussian()),
                        static_cast<float>(rng_.gaussian()));
      q = glm::normalize(fromRotationVector(e * sigma_r) * q);
    }
    r.position = p;
    r.orientation = q;
    r.time = t_measured;
    r.valid = true;
    r.status = ' ';
  }

  // Gloves: a pattern for the fingers, the body's own wrist.
  const float sigma_g = glm::radians(options_.glove_noise_deg);
  for (int side = 0; side < kHandCount; ++side) {
    GloveReading& g = state_.gloves[side];
    syntheticGlove(options_.glove, t_measured, options_.glove_period_s, g.angles);
    if (options_.glove_wrist_from_motion) {
      const int f = roles_[forearmRole(side)];
      const int h = roles_[handRole(side)];
      const glm::quat fw = glm::normalize(glm::quat_cast(glm::mat3(model_[f])));
      const glm::quat hw = glm::normalize(glm::quat_cast(glm::mat3(model_[h])));
      wristAngles(wrists_[side], fw, hw, g.angles[kWristPitch], g.angles[kWristYaw]);
    }
    if (sigma_g > 0.0f) {
      for (float& a : g.angles) a += static_cast<float>(rng_.gaussian()) * sigma_g;
    }
    g.time = t_measured;
    g.valid = true;
  }
  state_.time = t;
  state_.sequence = ++sequence_;
  frame = state_;
  ++tick_;
  return PollResult::frame();
}

std::string RigSimulator::describe() const {
  return fmt::format("simulated rig ({} joints, {:.2f} s at {} Hz{})", body_.jointCount(),
                     duration_, options_.rate_hz, options_.shared_rate ? " shared" : "");
}

}  // namespace vistel
