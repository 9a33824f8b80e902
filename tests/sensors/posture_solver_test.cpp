// The posture solver: exact recovery of arm postures four noiseless sensors determine (on a
// plain and on a scrambled-frame skeleton, directly and through the simulator), stability
// through a 0.5 s dropout, calibration, proportions, gloves, legs, clavicles, and no heap
// allocation per frame.
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <vector>

#include <gtest/gtest.h>

#include "common/sensors/calibration.hpp"
#include "common/sensors/posture_solver.hpp"
#include "common/sensors/random.hpp"
#include "common/sensors/rig_simulator.hpp"
#include "common/sensors/rotation_utils.hpp"
#include "tests/sensors/humanoid.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel {
namespace {

using test::Rig;

PostureSolver makeSolver(const Rig& rig, SolverOptions options,
                         const CalibrationOptions& copt = {}) {
  std::vector<SensorFrame> frames;
  for (int i = 0; i < 4; ++i)
    frames.push_back(test::exactFrame(rig.skeleton, rig.calibration, rig.sensors, 0.01 * i));
  auto cal = calibrateBody(rig.skeleton, rig.roles, rig.calibration, frames, copt);
  EXPECT_TRUE(cal.ok()) << (cal.ok() ? "" : cal.error().message);
  auto solver = PostureSolver::create(rig.skeleton, rig.roles, std::move(*cal), options);
  EXPECT_TRUE(solver.ok()) << (solver.ok() ? "" : solver.error().message);
  return std::move(*solver);
}

SolverOptions exactOptions() {
  SolverOptions o;
  o.filter = false;
  o.predict = false;
  return o;
}

glm::quat worldOf(const Skeleton& s, const Posture& p, int j) {
  std::vector<glm::mat4> model(static_cast<std::size_t>(s.jointCount()));
  poseSkeleton(s, p, model);
  return glm::normalize(glm::quat_cast(glm::mat3(model[static_cast<std::size_t>(j)])));
}

// An arm posture: upper arm up to 55 degrees off hanging (below where the clavicle lifts),
// elbow flexed 0..130 degrees about any axis across the upper arm, forearm rolled +-70.
void poseArm(const Rig& rig, Posture& p, int side, SimRandom& rng) {
  const int up = rig.roles[upperarmRole(side)];
  const int fo = rig.roles[forearmRole(side)];
  const auto pos = test::jointPositions(rig.skeleton, p);
  const glm::vec3 down =
      glm::normalize(pos[static_cast<std::size_t>(fo)] - pos[static_cast<std::size_t>(up)]);
  const glm::vec3 tilt_axis = glm::normalize(glm::cross(
      down, glm::vec3(static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian()),
                      static_cast<float>(rng.gaussian()))));
  const glm::quat swing =
      glm::angleAxis(glm::radians(55.0f) * static_cast<float>(rng.uniform()), tilt_axis);
  const glm::quat twist =
      glm::angleAxis(glm::radians(120.0f) * static_cast<float>(rng.uniform() - 0.5), down);
  const glm::quat w_up = swing * twist * worldOf(rig.skeleton, p, up);
  test::setWorldRotation(rig.skeleton, p, up, w_up);
  const auto pos2 = test::jointPositions(rig.skeleton, p);
  const glm::vec3 upper_dir =
      glm::normalize(pos2[static_cast<std::size_t>(fo)] - pos2[static_cast<std::size_t>(up)]);
  const glm::vec3 fore_dir =
      glm::normalize(pos2[static_cast<std::size_t>(rig.roles[handRole(side)])] -
                     pos2[static_cast<std::size_t>(fo)]);
  const glm::vec3 hinge = anyPerpendicular(upper_dir);
  const glm::quat flex =
      glm::angleAxis(glm::radians(130.0f) * static_cast<float>(rng.uniform()), hinge);
  const glm::quat roll =
      glm::angleAxis(glm::radians(140.0f) * static_cast<float>(rng.uniform() - 0.5), fore_dir);
  test::setWorldRotation(rig.skeleton, p, fo, flex * roll * worldOf(rig.skeleton, p, fo));
}

void expectArmsExact(const Rig& rig, const Posture& truth, const Posture& solved, float tol) {
  const auto want = test::jointPositions(rig.skeleton, truth);
  const auto got = test::jointPositions(rig.skeleton, solved);
  for (int side = 0; side < 2; ++side) {
    for (Role r : {upperarmRole(side), forearmRole(side), handRole(side)}) {
      const std::size_t j = static_cast<std::size_t>(rig.roles[r]);
      EXPECT_LT(glm::distance(want[j], got[j]), tol) << roleName(r);
    }
    // The hand's rotation too (the wrist is not bent in these postures).
    const int h = rig.roles[handRole(side)];
    EXPECT_LT(test::angleDegrees(worldOf(rig.skeleton, truth, h), worldOf(rig.skeleton, solved, h)),
              0.05f);
  }
  const std::size_t head = static_cast<std::size_t>(rig.roles[Role::kHead]);
  EXPECT_LT(glm::distance(want[head], got[head]), tol);
}

class SolverExact : public ::testing::TestWithParam<bool> {};

TEST_P(SolverExact, RecoversArmPosturesFromNoiselessSensors) {
  const Rig rig = test::makeRig(GetParam());
  PostureSolver solver = makeSolver(rig, exactOptions());
  SimRandom rng(3);
  Posture solved;
  for (int k = 0; k < 60; ++k) {
    Posture truth = rig.calibration;
    // Half the postures also move the whole body rigidly (walk and turn): the arms must
    // still be exact, since the chest sensor fixes the shoulders.
    if (k % 2 == 1) {
      truth.root_translation += glm::vec3(static_cast<float>(rng.uniform() - 0.5), 0.0f,
                                          static_cast<float>(rng.uniform() - 0.5));
      test::setWorldRotation(
          rig.skeleton, truth, 0,
          glm::angleAxis(static_cast<float>(rng.uniform() * 6.0), glm::vec3(0, 1, 0)) *
              worldOf(rig.skeleton, truth, 0));
    }
    poseArm(rig, truth, 0, rng);
    poseArm(rig, truth, 1, rng);
    solver.solve(test::exactFrame(rig.skeleton, truth, rig.sensors, 0.1 * (k + 1)), solved);
    SCOPED_TRACE(k);
    expectArmsExact(rig, truth, solved, 0.001f);
  }
}

TEST_P(SolverExact, ThroughTheSimulator) {
  const Rig rig = test::makeRig(GetParam());
  // A moving body: both arms swing and bend, the whole body walks and turns.
  const PostureSampler sampler = [&rig](double t, Posture& out) {
    out = rig.calibration;
    const float s = static_cast<float>(t);
    out.root_translation += glm::vec3(0.3f * std::sin(s), 0.0f, 0.2f * s);
    test::setWorldRotation(
        rig.skeleton, out, 0,
        glm::angleAxis(0.5f * s, glm::vec3(0, 1, 0)) * worldOf(rig.skeleton, out, 0));
    for (int side = 0; side < 2; ++side) {
      const int up = rig.roles[upperarmRole(side)];
      const int fo = rig.roles[forearmRole(side)];
      const float ph = side == 0 ? 0.0f : 1.3f;
      test::setWorldRotation(rig.skeleton, out, up,
                             glm::angleAxis(0.6f * std::sin(2.0f * s + ph), glm::vec3(1, 0, 0)) *
                                 glm::angleAxis(0.3f * std::sin(1.3f * s), glm::vec3(0, 0, 1)) *
                                 worldOf(rig.skeleton, out, up));
      test::setWorldRotation(
          rig.skeleton, out, fo,
          glm::angleAxis(0.8f + 0.7f * std::sin(3.0f * s + ph), glm::vec3(1, 0, 0)) *
              worldOf(rig.skeleton, out, fo));
    }
  };
  SimOptions sim_options = noiselessSimOptions();
  sim_options.shared_rate = false;
  auto sim = RigSimulator::create(rig.skeleton, rig.roles, sampler, 2.0, sim_options);
  ASSERT_TRUE(sim.ok()) << sim.error().message;
  SensorFrame frame;
  std::vector<SensorFrame> calib;
  ASSERT_TRUE((*sim)->poll(0.0, frame).isFrame());
  calib.push_back(frame);
  auto cal = calibrateBody(rig.skeleton, rig.roles, (*sim)->calibrationPosture(), calib, {});
  ASSERT_TRUE(cal.ok()) << cal.error().message;
  auto solver = PostureSolver::create(rig.skeleton, rig.roles, *cal, exactOptions());
  ASSERT_TRUE(solver.ok());
  Posture solved, truth;
  int frames = 0;
  while ((*sim)->poll(0.0, frame).isFrame()) {
    solver->solve(frame, solved);
    (*sim)->truth(frame.time, truth);
    SCOPED_TRACE(frame.time);
    expectArmsExact(rig, truth, solved, 0.001f);
    ++frames;
  }
  EXPECT_EQ(frames, 240);
}

INSTANTIATE_TEST_SUITE_P(Skeletons, SolverExact, ::testing::Values(false, true),
                         [](const auto& param_info) {
                           return param_info.param ? "ScrambledFrames" : "PlainFrames";
                         });

TEST(Calibration, FindsTheMountsAndFailsWithoutAStation) {
  const Rig rig = test::makeRig(true);
  std::vector<SensorFrame> frames = {
      test::exactFrame(rig.skeleton, rig.calibration, rig.sensors, 0.0)};
  auto cal = calibrateBody(rig.skeleton, rig.roles, rig.calibration, frames, {});
  ASSERT_TRUE(cal.ok());
  for (int s = 0; s < kUpperBodySiteCount; ++s) {
    const StationCalibration& sc = cal->stations[static_cast<std::size_t>(s)];
    EXPECT_EQ(sc.segment, rig.sensors[static_cast<std::size_t>(s)].segment);
    EXPECT_LT(glm::distance(sc.offset, rig.sensors[static_cast<std::size_t>(s)].local_offset),
              1e-5f);
    // X is the inverse of the sensor's rotation on its segment.
    EXPECT_LT(test::angleDegrees(glm::inverse(sc.sensor_to_segment),
                                 rig.sensors[static_cast<std::size_t>(s)].local_rotation),
              0.01f);
  }
  frames[0].station(BodySite::kLeftWrist).valid = false;
  auto missing = calibrateBody(rig.skeleton, rig.roles, rig.calibration, frames, {});
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("left_wrist"), std::string::npos);
  EXPECT_FALSE(calibrateBody(rig.skeleton, rig.roles, rig.calibration, {}, {}).ok());
}

TEST(Calibration, EstimatesProportionsAndFacing) {
  const Rig rig = test::makeRig(false);
  // A participant 10 % larger in every bone, standing 2 m away, turned 90 degrees.
  Skeleton big = rig.skeleton;
  for (std::size_t j = 1; j < big.rest_local.size(); ++j) big.rest_local[j].translation *= 1.1f;
  big.rest_local[0].translation *= 1.1f;
  auto big_roles = resolveJointRoles(big, nullptr);
  ASSERT_TRUE(big_roles.ok());
  Posture pose = standardCalibrationPosture(big, *big_roles);
  pose.root_translation += glm::vec3(2.0f, 0.0f, -1.0f);
  test::setWorldRotation(big, pose, 0, glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0)));
  std::vector<glm::mat4> model(static_cast<std::size_t>(big.jointCount()));
  poseSkeleton(big, pose, model);
  // Mount offsets scale with the body too.
  auto mounts = defaultSensorMounts();
  for (auto& m : mounts) m.offset *= 1.1f;
  const auto sensors = attachSensors(*big_roles, model, mounts);
  std::vector<SensorFrame> frames = {test::exactFrame(big, pose, sensors, 0.0)};
  CalibrationOptions options;
  options.estimate_proportions = true;
  options.alignment = AlignmentMode::kFacing;
  options.floor_height = 0.0f;
  auto cal = calibrateBody(rig.skeleton, rig.roles, rig.calibration, frames, options);
  ASSERT_TRUE(cal.ok());
  EXPECT_NEAR(cal->proportions.arm[0], 1.1f, 0.01f);
  EXPECT_NEAR(cal->proportions.arm[1], 1.1f, 0.01f);
  EXPECT_NEAR(cal->proportions.torso, 1.1f, 0.01f);
  EXPECT_NEAR(cal->proportions.height, 1.1f, 0.03f);
  // Facing: the participant's left (+Z after the turn... ) maps onto the avatar's +X.
  const glm::vec3 left_participant =
      cal->align_rotation *
      (glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0)) * glm::vec3(1, 0, 0));
  EXPECT_GT(left_participant.x, 0.999f);
  // Solving the calibration frame on the avatar gives the avatar's calibration posture.
  auto solver = PostureSolver::create(rig.skeleton, rig.roles, *cal, exactOptions());
  ASSERT_TRUE(solver.ok());
  Posture solved;
  solver->solve(frames[0], solved);
  const auto want = test::jointPositions(rig.skeleton, rig.calibration);
  const auto got = test::jointPositions(rig.skeleton, solved);
  for (Role r : {Role::kHead, Role::kLHand, Role::kRHand, Role::kLForearm, Role::kHips}) {
    const std::size_t j = static_cast<std::size_t>(rig.roles[r]);
    EXPECT_LT(glm::distance(want[j], got[j]), 0.02f) << roleName(r);
  }
}

// Runs the solver on a simulated moving body (default noise, latency and shared rate) with
// an optional dropout; returns per frame the solved joint positions and the true ones.
struct Run {
  std::vector<std::vector<glm::vec3>> solved, truth;
  std::vector<double> time;
  bool held_seen = false;
};

Run runMoving(const Rig& rig, const std::vector<StationDropout>& dropouts, BodySite watched) {
  const PostureSampler sampler = [&rig](double t, Posture& out) {
    out = rig.calibration;
    const float s = static_cast<float>(t);
    for (int side = 0; side < 2; ++side) {
      const int up = rig.roles[upperarmRole(side)];
      const int fo = rig.roles[forearmRole(side)];
      test::setWorldRotation(rig.skeleton, out, up,
                             glm::angleAxis(0.5f * std::sin(2.5f * s), glm::vec3(1, 0, 0)) *
                                 worldOf(rig.skeleton, out, up));
      test::setWorldRotation(rig.skeleton, out, fo,
                             glm::angleAxis(0.9f + 0.5f * std::sin(3.0f * s), glm::vec3(1, 0, 0)) *
                                 worldOf(rig.skeleton, out, fo));
    }
    const int chest = rig.roles[Role::kChest];
    test::setWorldRotation(rig.skeleton, out, chest,
                           glm::angleAxis(0.2f * std::sin(1.5f * s), glm::vec3(1, 0, 0)) *
                               worldOf(rig.skeleton, out, chest));
  };
  SimOptions o;  // default noise, latency and shared rate
  o.hold_s = 0.3;
  o.dropouts = dropouts;
  auto sim = RigSimulator::create(rig.skeleton, rig.roles, sampler, 3.0, o);
  EXPECT_TRUE(sim.ok());
  Run run;
  SensorFrame frame;
  std::vector<SensorFrame> calib;
  while (calib.size() < 30 && (*sim)->poll(0.0, frame).isFrame()) calib.push_back(frame);
  auto cal = calibrateBody(rig.skeleton, rig.roles, (*sim)->calibrationPosture(), calib, {});
  EXPECT_TRUE(cal.ok());
  auto solver = PostureSolver::create(rig.skeleton, rig.roles, *cal, SolverOptions{});
  EXPECT_TRUE(solver.ok());
  Posture solved, truth;
  while ((*sim)->poll(0.0, frame).isFrame()) {
    solver->solve(frame, solved);
    (*sim)->truth(frame.time, truth);
    run.solved.push_back(test::jointPositions(rig.skeleton, solved));
    run.truth.push_back(test::jointPositions(rig.skeleton, truth));
    run.time.push_back(frame.time);
    if (solver->heldStations() & (1u << static_cast<int>(watched))) run.held_seen = true;
  }
  return run;
}

float worstStep(const Run& run) {
  float worst = 0.0f;
  for (std::size_t k = 1; k < run.solved.size(); ++k) {
    for (std::size_t j = 0; j < run.solved[k].size(); ++j) {
      worst = std::max(worst, glm::distance(run.solved[k][j], run.solved[k - 1][j]));
    }
  }
  return worst;
}

float worstError(const Rig& rig, const Run& run, double from, double to) {
  float worst = 0.0f;
  for (std::size_t k = 0; k < run.solved.size(); ++k) {
    if (run.time[k] < from || run.time[k] > to) continue;
    for (Role r : {Role::kHead, Role::kLHand, Role::kRHand, Role::kLForearm, Role::kRForearm}) {
      const std::size_t j = static_cast<std::size_t>(rig.roles[r]);
      worst = std::max(worst, glm::distance(run.solved[k][j], run.truth[k][j]));
    }
  }
  return worst;
}

// Drops one station for 0.5 s (from t = 1.3 s): the output stays finite and as smooth as
// without the dropout, and is back to the undisturbed accuracy 0.5 s after the station
// returns.
void checkDropout(BodySite site) {
  const Rig rig = test::makeRig(false);
  const Run base = runMoving(rig, {}, site);
  const Run drop = runMoving(rig, {{site, 1.3, 0.5}}, site);
  ASSERT_EQ(base.solved.size(), drop.solved.size());
  EXPECT_TRUE(drop.held_seen);
  for (const auto& frame : drop.solved) {
    for (const glm::vec3& p : frame)
      ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
  }
  const float base_step = worstStep(base);
  const float drop_step = worstStep(drop);
  EXPECT_LT(drop_step, base_step + 0.005f) << bodySiteName(site) << ": base " << base_step;
  const float base_after = worstError(rig, base, 2.3, 10.0);
  const float drop_after = worstError(rig, drop, 2.3, 10.0);
  EXPECT_LT(drop_after, base_after + 0.002f) << bodySiteName(site) << ": base " << base_after;
  EXPECT_LT(base_after, 0.04f);
  // While held, the dropped segment stays near where it was (no runaway extrapolation).
  float drift = 0.0f;
  std::size_t start = 0;
  while (start < drop.time.size() && drop.time[start] < 1.3) ++start;
  const std::size_t j =
      static_cast<std::size_t>(rig.roles[site == BodySite::kHead    ? Role::kHead
                                         : site == BodySite::kChest ? Role::kUpperChest
                                                                    : Role::kRHand]);
  for (std::size_t k = start; k < drop.time.size() && drop.time[k] < 1.8; ++k) {
    drift = std::max(drift, glm::distance(drop.solved[k][j], drop.solved[start][j]));
  }
  EXPECT_LT(drift, 0.12f);
}

TEST(SolverDropout, WristStationOutForHalfASecond) { checkDropout(BodySite::kRightWrist); }
TEST(SolverDropout, ChestStationOutForHalfASecond) { checkDropout(BodySite::kChest); }
TEST(SolverDropout, HeadStationOutForHalfASecond) { checkDropout(BodySite::kHead); }

TEST(Solver, ClavicleLiftsWhenTheHandRisesHigh) {
  const Rig rig = test::makeRig(false);
  PostureSolver solver = makeSolver(rig, exactOptions());
  float last_lift = -1.0f;
  const int clav = rig.roles[Role::kLClavicle];
  for (int k = 0; k <= 6; ++k) {
    Posture truth = rig.calibration;
    const int up = rig.roles[Role::kLUpperarm];
    // Raise the left arm sideways from hanging (0) to straight up (180 degrees).
    test::setWorldRotation(rig.skeleton, truth, up,
                           glm::angleAxis(glm::radians(30.0f * k), glm::vec3(0, 0, 1)) *
                               worldOf(rig.skeleton, truth, up));
    Posture solved;
    solver.solve(test::exactFrame(rig.skeleton, truth, rig.sensors, 0.1 * (k + 1)), solved);
    const float lift = test::angleDegrees(worldOf(rig.skeleton, solved, clav),
                                          worldOf(rig.skeleton, rig.calibration, clav));
    if (k <= 2) {
      EXPECT_LT(lift, 0.01f);  // up to 60 degrees: no lift
    }
    EXPECT_GE(lift, last_lift - 1e-3f);
    last_lift = lift;
  }
  EXPECT_GT(last_lift, 15.0f);
}

TEST(Solver, GlovesCurlTheFingersTowardThePalm) {
  const Rig rig = test::makeRig(true);
  PostureSolver solver = makeSolver(rig, exactOptions());
  SensorFrame frame = test::exactFrame(rig.skeleton, rig.calibration, rig.sensors, 1.0);
  Posture open, fist;
  solver.solve(frame, open);
  const auto p_open = test::jointPositions(rig.skeleton, open);
  const auto p_cal = test::jointPositions(rig.skeleton, rig.calibration);
  for (int side = 0; side < 2; ++side) {
    for (int f = 0; f < 5; ++f) {
      for (int k = 0; k < 3; ++k) {
        const std::size_t j = static_cast<std::size_t>(rig.roles[fingerRole(side, f, k)]);
        EXPECT_LT(glm::distance(p_open[j], p_cal[j]), 1e-4f);
      }
    }
  }
  for (GloveReading& g : frame.gloves) {
    g.valid = true;
    g.angles.fill(0.0f);
    for (int s : {kIndexMpj, kIndexPij, kIndexDij, kPinkyMpj, kPinkyPij, kPinkyDij})
      g.angles[s] = glm::radians(80.0f);
  }
  frame.time += 0.01;
  solver.solve(frame, fist);
  const auto p_fist = test::jointPositions(rig.skeleton, fist);
  for (int side = 0; side < 2; ++side) {
    // In the calibration posture the palms face the body's midline.
    const float medial = side == 0 ? -1.0f : 1.0f;
    const std::size_t tip = static_cast<std::size_t>(rig.roles[fingerRole(side, 1, 2)]);
    const std::size_t hand = static_cast<std::size_t>(rig.roles[handRole(side)]);
    EXPECT_GT(medial * (p_fist[tip].x - p_open[tip].x), 0.03f) << side;
    EXPECT_LT(glm::distance(p_fist[hand], p_open[hand]), 1e-4f);
    const std::size_t middle_tip = static_cast<std::size_t>(rig.roles[fingerRole(side, 2, 2)]);
    EXPECT_LT(glm::distance(p_fist[middle_tip], p_open[middle_tip]), 1e-4f);
  }
}

TEST(Solver, GloveWristAnglesTurnTheHandAsTheSimulatorReadsThem) {
  const Rig rig = test::makeRig(true);
  PostureSolver solver = makeSolver(rig, exactOptions());
  SimRandom rng(4);
  for (int k = 0; k < 20; ++k) {
    Posture truth = rig.calibration;
    const int fo = rig.roles[Role::kRForearm];
    const int hand = rig.roles[Role::kRHand];
    const auto pos = test::jointPositions(rig.skeleton, truth);
    const glm::vec3 axis =
        glm::normalize(pos[static_cast<std::size_t>(hand)] - pos[static_cast<std::size_t>(fo)]);
    // A bend without twist about the forearm axis: what a glove can measure.
    const glm::vec3 bend_axis = glm::normalize(glm::cross(
        axis, glm::vec3(static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian()),
                        static_cast<float>(rng.gaussian()))));
    const glm::quat w_hand =
        glm::angleAxis(glm::radians(70.0f) * static_cast<float>(rng.uniform()), bend_axis) *
        worldOf(rig.skeleton, truth, hand);
    test::setWorldRotation(rig.skeleton, truth, hand, w_hand);
    SensorFrame frame = test::exactFrame(rig.skeleton, truth, rig.sensors, 0.1 * (k + 1));
    const glm::quat w_fore = worldOf(rig.skeleton, truth, fo);
    const glm::vec3 local_axis = glm::inverse(w_fore) * axis;
    std::vector<glm::vec3> cal_pos = test::jointPositions(rig.skeleton, rig.calibration);
    const WristModel wrist = makeWristModel(
        1, bodyFrameAt(rig.roles, cal_pos), worldOf(rig.skeleton, rig.calibration, fo),
        worldOf(rig.skeleton, rig.calibration, hand), local_axis);
    GloveReading& g = frame.glove(Hand::kRight);
    g.valid = true;
    wristAngles(wrist, w_fore, w_hand, g.angles[kWristPitch], g.angles[kWristYaw]);
    Posture solved;
    solver.solve(frame, solved);
    EXPECT_LT(test::angleDegrees(worldOf(rig.skeleton, solved, hand), w_hand), 0.05f) << k;
  }
}

TEST(Solver, StandingFeetStayOnTheFloorAndSeatedThighsAreLevel) {
  const Rig rig = test::makeRig(false);
  // Crouch: the whole body 20 cm lower.
  Posture crouch = rig.calibration;
  crouch.root_translation.y -= 0.2f;
  const auto cal_pos = test::jointPositions(rig.skeleton, rig.calibration);
  PostureSolver standing = makeSolver(rig, exactOptions());
  Posture solved;
  standing.solve(test::exactFrame(rig.skeleton, crouch, rig.sensors, 1.0), solved);
  auto pos = test::jointPositions(rig.skeleton, solved);
  for (int side = 0; side < 2; ++side) {
    const std::size_t foot = static_cast<std::size_t>(rig.roles[footRole(side)]);
    const std::size_t knee = static_cast<std::size_t>(rig.roles[shinRole(side)]);
    EXPECT_NEAR(pos[foot].y, cal_pos[foot].y, 1e-3f);
    EXPECT_GT(pos[knee].z, cal_pos[knee].z + 0.05f);  // knees bend forward
  }
  SolverOptions seated_options = exactOptions();
  seated_options.stance = Stance::kSeated;
  PostureSolver seated = makeSolver(rig, seated_options);
  seated.solve(test::exactFrame(rig.skeleton, crouch, rig.sensors, 1.0), solved);
  pos = test::jointPositions(rig.skeleton, solved);
  for (int side = 0; side < 2; ++side) {
    const std::size_t hip = static_cast<std::size_t>(rig.roles[thighRole(side)]);
    const std::size_t knee = static_cast<std::size_t>(rig.roles[shinRole(side)]);
    const std::size_t foot = static_cast<std::size_t>(rig.roles[footRole(side)]);
    EXPECT_NEAR(pos[knee].y, pos[hip].y, 1e-3f);
    EXPECT_NEAR(pos[foot].x, pos[knee].x, 1e-3f);
    EXPECT_NEAR(pos[foot].z, pos[knee].z, 1e-3f);
  }
}

TEST(Solver, AllocatesNothingPerFrame) {
  const Rig rig = test::makeRig(false);
  PostureSolver solver = makeSolver(rig, SolverOptions{});
  std::vector<SensorFrame> frames;
  for (int k = 0; k < 50; ++k) {
    Posture p = rig.calibration;
    p.root_translation.x += 0.01f * static_cast<float>(k);
    frames.push_back(test::exactFrame(rig.skeleton, p, rig.sensors, 0.01 * k));
    frames.back().gloves[0].valid = true;
  }
  Posture out;
  solver.solve(frames[0], out);  // sizes `out`
  test::AllocationCounter counter;
  for (std::size_t k = 1; k < frames.size(); ++k) solver.solve(frames[k], out);
  EXPECT_EQ(counter.count(), 0);
}

}  // namespace
}  // namespace vistel
