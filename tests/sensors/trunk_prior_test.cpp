// The solver's trunk prior (SolverOptions::hips_cutoff_hz): a participant standing still
// behind a noisy tracker, a slowly bowing one and a walking one. The prior steadies the hips
// and legs of the still body, lets a bow (a turn of the trunk about the hips) through, and
// follows walking.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "common/sensors/calibration.hpp"
#include "common/sensors/posture_solver.hpp"
#include "common/sensors/rig_simulator.hpp"
#include "tests/sensors/humanoid.hpp"

namespace vistel {
namespace {

struct TrunkRun {
  double hips_jerk = 0.0;    // mean |third difference| / dt^3 of the hips, m/s^3
  double hips_error = 0.0;   // mean distance of the solved hips from the true ones, m
  double chest_error = 0.0;  // ... of the chest segment
};

TrunkRun solveWith(float hips_cutoff_hz, const PostureSampler& sampler, const Skeleton& skeleton,
                   const JointRoles& roles) {
  SimOptions sim_options;  // default FASTRAK-like noise, shared 120 Hz
  sim_options.hold_s = 0.5;
  auto sim = RigSimulator::create(skeleton, roles, sampler, 3.0, sim_options);
  EXPECT_TRUE(sim.ok());
  SensorFrame frame;
  std::vector<SensorFrame> calib, frames;
  while ((*sim)->poll(0.0, frame).isFrame()) {
    if (frame.time < 0.5) {
      if (frame.time >= 0.1) calib.push_back(frame);
    }
    frames.push_back(frame);
  }
  auto cal = calibrateBody(skeleton, roles, (*sim)->calibrationPosture(), calib, {});
  EXPECT_TRUE(cal.ok());
  SolverOptions options;
  options.hips_cutoff_hz = hips_cutoff_hz;
  auto solver = PostureSolver::create(skeleton, roles, *cal, options);
  EXPECT_TRUE(solver.ok());
  const int hips = roles[Role::kHips];
  const int chest = roles.chestSegment();
  std::vector<glm::vec3> solved_hips;
  TrunkRun run;
  int scored = 0;
  Posture solved, truth;
  for (const SensorFrame& f : frames) {
    solver->solve(f, solved);
    if (f.time < 1.0) continue;  // settled
    (*sim)->truth(f.time, truth);
    const auto a = test::jointPositions(skeleton, solved);
    const auto b = test::jointPositions(skeleton, truth);
    solved_hips.push_back(a[static_cast<std::size_t>(hips)]);
    run.hips_error +=
        glm::distance(a[static_cast<std::size_t>(hips)], b[static_cast<std::size_t>(hips)]);
    run.chest_error +=
        glm::distance(a[static_cast<std::size_t>(chest)], b[static_cast<std::size_t>(chest)]);
    ++scored;
  }
  const double dt = 1.0 / sim_options.rate_hz;
  for (std::size_t k = 0; k + 3 < solved_hips.size(); ++k) {
    run.hips_jerk += glm::length(solved_hips[k + 3] - 3.0f * solved_hips[k + 2] +
                                 3.0f * solved_hips[k + 1] - solved_hips[k]);
  }
  run.hips_jerk /= static_cast<double>(solved_hips.size() - 3) * dt * dt * dt;
  run.hips_error /= scored;
  run.chest_error /= scored;
  return run;
}

class TrunkPrior : public ::testing::Test {
 protected:
  void SetUp() override {
    skeleton_ = test::makeHumanoid();
    auto roles = resolveJointRoles(skeleton_, nullptr);
    ASSERT_TRUE(roles.ok());
    roles_ = *roles;
    calibration_ = standardCalibrationPosture(skeleton_, roles_);
  }
  Skeleton skeleton_;
  JointRoles roles_{};
  Posture calibration_;
};

TEST_F(TrunkPrior, SteadiesAStillBody) {
  const PostureSampler still = [this](double, Posture& out) { out = calibration_; };
  const TrunkRun off = solveWith(0.0f, still, skeleton_, roles_);
  const TrunkRun on = solveWith(1.0f, still, skeleton_, roles_);
  EXPECT_LT(on.hips_jerk, 0.5 * off.hips_jerk) << off.hips_jerk << " -> " << on.hips_jerk;
}

TEST_F(TrunkPrior, LetsABowThroughAndFollowsWalking) {
  const int spine = roles_[Role::kSpine];
  // A bow: the spine leans forward 30 degrees and back over 2 s; the hips stay.
  const PostureSampler bow = [this, spine](double t, Posture& out) {
    out = calibration_;
    const float a = glm::radians(30.0f) * 0.5f * (1.0f - std::cos(glm::pi<float>() * t));
    test::setWorldRotation(skeleton_, out, spine, glm::angleAxis(a, glm::vec3(1, 0, 0)));
  };
  const TrunkRun bow_off = solveWith(0.0f, bow, skeleton_, roles_);
  const TrunkRun bow_on = solveWith(1.0f, bow, skeleton_, roles_);
  EXPECT_LT(bow_on.chest_error, bow_off.chest_error + 0.01)
      << bow_off.chest_error << " -> " << bow_on.chest_error;
  // Walking at 1 m/s: the hips' corner rises with their speed, so they keep up.
  const PostureSampler walk = [this](double t, Posture& out) {
    out = calibration_;
    out.root_translation += glm::vec3(0.0f, 0.0f, static_cast<float>(t));
  };
  const TrunkRun walk_on = solveWith(1.0f, walk, skeleton_, roles_);
  EXPECT_LT(walk_on.hips_error, 0.03) << walk_on.hips_error;
}

}  // namespace
}  // namespace vistel
