// Foot trackers (issue 21, six sensors): four-station solves are what they were before the
// feet existed; with a tracker on each foot the legs follow the body (exactly, from noiseless
// sensors, on a humanoid; far closer than the standing heuristic on the shared clips); a
// foot station that never reports is not worn, not lost.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "common/base/hash.hpp"
#include "common/sensors/calibration.hpp"
#include "common/sensors/clip_solve.hpp"
#include "common/sensors/io/posture_source.hpp"
#include "common/sensors/posture_solver.hpp"
#include "common/sensors/recording.hpp"
#include "common/sensors/rig_simulator.hpp"
#include "tests/sensors/humanoid.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

using test::Rig;

PostureSolver makeSolver(const Rig& rig, bool feet, SolverOptions options = {}) {
  options.filter = false;
  options.predict = false;
  std::vector<SensorFrame> frames;
  for (int i = 0; i < 4; ++i) {
    frames.push_back(test::exactFrame(rig.skeleton, rig.calibration, rig.sensors, 0.01 * i, feet));
  }
  auto cal = calibrateBody(rig.skeleton, rig.roles, rig.calibration, frames, {});
  EXPECT_TRUE(cal.ok()) << (cal.ok() ? "" : cal.error().message);
  auto solver = PostureSolver::create(rig.skeleton, rig.roles, std::move(*cal), options);
  EXPECT_TRUE(solver.ok());
  return std::move(*solver);
}

TEST(FootTrackers, FootStationsAreOptionalAndNeverHeldWhenNotWorn) {
  const Rig rig = test::makeRig(true);
  PostureSolver four = makeSolver(rig, false);
  EXPECT_FALSE(four.footTracked(0));
  EXPECT_FALSE(four.footTracked(1));
  EXPECT_FALSE(
      four.calibration().stations[static_cast<std::size_t>(BodySite::kLeftFoot)].calibrated);
  Posture out;
  four.solve(test::exactFrame(rig.skeleton, rig.calibration, rig.sensors, 1.0), out);
  EXPECT_EQ(four.heldStations(), 0u);

  PostureSolver six = makeSolver(rig, true);
  EXPECT_TRUE(six.footTracked(0));
  EXPECT_TRUE(six.footTracked(1));
  // The foot sensors' offsets on the feet are found.
  for (BodySite site : {BodySite::kLeftFoot, BodySite::kRightFoot}) {
    const std::size_t s = static_cast<std::size_t>(site);
    const StationCalibration& sc = six.calibration().stations[s];
    EXPECT_TRUE(sc.calibrated);
    EXPECT_EQ(sc.segment, rig.sensors[s].segment);
    EXPECT_LT(glm::distance(sc.offset, rig.sensors[s].local_offset), 1e-5f);
  }
  // A worn foot station that drops out is held like any other.
  SensorFrame f = test::exactFrame(rig.skeleton, rig.calibration, rig.sensors, 1.0, true);
  six.solve(f, out);
  f = test::exactFrame(rig.skeleton, rig.calibration, rig.sensors, 1.5, true);
  f.station(BodySite::kRightFoot).valid = false;
  six.solve(f, out);
  EXPECT_EQ(six.heldStations(), 1u << static_cast<int>(BodySite::kRightFoot));
}

TEST(FootTrackers, TrackedLegsFollowSittingAndSteppingExactly) {
  const Rig rig = test::makeRig(true);
  PostureSolver six = makeSolver(rig, true);
  PostureSolver four = makeSolver(rig, false);
  const glm::vec3 left(1, 0, 0);  // the humanoid faces +Z, its left is +X
  const glm::vec3 up(0, 1, 0);
  // Seated: hips 45 cm lower, thighs forward (90 degrees), shins down, the left leg turned
  // out 20 degrees (knee and foot), the feet pitched 10 degrees; then a step: the right thigh
  // 35 degrees forward, the knee bent 50 degrees, the foot lifted.
  std::vector<glm::mat4> cal_model(static_cast<std::size_t>(rig.skeleton.jointCount()));
  poseSkeleton(rig.skeleton, rig.calibration, cal_model);
  auto calWorld = [&](int j) {
    return glm::normalize(glm::quat_cast(glm::mat3(cal_model[static_cast<std::size_t>(j)])));
  };
  for (int pose = 0; pose < 2; ++pose) {
    Posture p = rig.calibration;
    for (int side = 0; side < 2; ++side) {
      const int th = rig.roles[thighRole(side)];
      const int sh = rig.roles[shinRole(side)];
      const int ft = rig.roles[footRole(side)];
      if (pose == 0) {
        const glm::quat yaw = glm::angleAxis(glm::radians(side == 0 ? 20.0f : 0.0f), up);
        test::setWorldRotation(rig.skeleton, p, th,
                               yaw * glm::angleAxis(glm::radians(-90.0f), left) * calWorld(th));
        test::setWorldRotation(rig.skeleton, p, sh, yaw * calWorld(sh));
        test::setWorldRotation(rig.skeleton, p, ft,
                               yaw * glm::angleAxis(glm::radians(-10.0f), left) * calWorld(ft));
      } else if (side == 1) {
        const glm::quat thigh = glm::angleAxis(glm::radians(-35.0f), left);
        test::setWorldRotation(rig.skeleton, p, th, thigh * calWorld(th));
        const glm::quat shin = glm::angleAxis(glm::radians(15.0f), left);
        test::setWorldRotation(rig.skeleton, p, sh, shin * calWorld(sh));
        test::setWorldRotation(rig.skeleton, p, ft, shin * calWorld(ft));
      }
    }
    if (pose == 0) p.root_translation.y -= 0.45f;
    const SensorFrame frame = test::exactFrame(rig.skeleton, p, rig.sensors, 1.0 + pose, true);
    Posture solved, inferred;
    six.solve(frame, solved);
    four.solve(frame, inferred);
    const auto truth = test::jointPositions(rig.skeleton, p);
    const auto got = test::jointPositions(rig.skeleton, solved);
    const auto guess = test::jointPositions(rig.skeleton, inferred);
    for (int side = 0; side < 2; ++side) {
      // (A straight leg's knee may come forward by a few millimetres: the IK's soft reach.)
      const bool straight = pose == 1 && side == 0;
      for (Role r : {shinRole(side), footRole(side), toesRole(side)}) {
        const std::size_t j = static_cast<std::size_t>(rig.roles[r]);
        const float tolerance = straight && r == shinRole(side) ? 1e-2f : 2e-3f;
        EXPECT_LT(glm::distance(got[j], truth[j]), tolerance) << pose << " " << side;
      }
      const std::size_t ft = static_cast<std::size_t>(rig.roles[footRole(side)]);
      if (pose == 0 || side == 1) {
        EXPECT_GT(glm::distance(guess[ft], truth[ft]), 0.05f);  // the heuristic cannot know
      }
    }
  }
}

TEST(FootTrackers, SimulatorSharesTheRateAmongTheWornStations) {
  const Rig rig = test::makeRig(true);
  const Posture still = rig.calibration;
  for (bool feet : {false, true}) {
    SimOptions o = noiselessSimOptions();
    o.foot_trackers = feet;
    auto sim = RigSimulator::create(
        rig.skeleton, rig.roles, [&](double, Posture& out) { out = still; }, 1.0, o);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    const int worn = feet ? kBodySiteCount : kUpperBodySiteCount;
    std::array<int, kBodySiteCount> updates{};
    SensorFrame prev, frame;
    for (int tick = 0; tick < 2 * worn; ++tick) {
      ASSERT_TRUE((*sim)->poll(0.0, frame).isFrame());
      int fresh = 0;
      for (int s = 0; s < kBodySiteCount; ++s) {
        const StationReading& r = frame.stations[static_cast<std::size_t>(s)];
        const bool is_new = r.valid && (!prev.stations[static_cast<std::size_t>(s)].valid ||
                                        r.time != prev.stations[static_cast<std::size_t>(s)].time);
        fresh += is_new;
        updates[static_cast<std::size_t>(s)] += is_new;
      }
      EXPECT_EQ(fresh, 1) << tick;  // one station per tick
      prev = frame;
    }
    for (int s = 0; s < kBodySiteCount; ++s) {
      EXPECT_EQ(updates[static_cast<std::size_t>(s)], s < worn ? 2 : 0) << feet << " " << s;
    }
    if (feet) {
      // The foot sensor reads where it is mounted on the foot.
      glm::vec3 p;
      glm::quat q;
      std::vector<glm::mat4> model(static_cast<std::size_t>(rig.skeleton.jointCount()));
      poseSkeleton(rig.skeleton, still, model);
      sensorPose((*sim)->sensors()[static_cast<std::size_t>(BodySite::kLeftFoot)], model, p, q);
      EXPECT_LT(glm::distance(frame.station(BodySite::kLeftFoot).position, p), 1e-6f);
    }
  }
}

struct Score {
  PostureMetrics m;
  double feet_m = 0.0;  // mean position error of the feet and toes joints
};

// Default noise. Six stations share a 240 Hz tracker (40 Hz each; the four share 120 Hz, 30 Hz
// each): a multiple of the clips' frame rates, so the solved frames do not alias.
Score scoreClip(const ClipBody& body, bool feet) {
  ClipSolveOptions options;
  options.sim.foot_trackers = feet;
  if (feet) options.sim.rate_hz = 240.0;
  auto solved = solveClip(body, options);
  EXPECT_TRUE(solved.ok()) << (solved.ok() ? "" : solved.error().message);
  if (!solved.ok()) return {};
  const std::vector<Posture> truth = clipPostures(body.clip);
  Score s;
  s.m = measurePostures(body.skeleton, body.roles, truth, solved->postures, body.clip.frame_time);
  double sum = 0.0;
  int n = 0;
  for (std::size_t f = 0; f < truth.size(); ++f) {
    const auto a = test::jointPositions(body.skeleton, truth[f]);
    const auto b = test::jointPositions(body.skeleton, solved->postures[f]);
    for (int side = 0; side < 2; ++side) {
      for (Role r : {footRole(side), toesRole(side)}) {
        if (!body.roles.has(r)) continue;
        const std::size_t j = static_cast<std::size_t>(body.roles[r]);
        sum += glm::distance(a[j], b[j]);
        ++n;
      }
    }
  }
  s.feet_m = n > 0 ? sum / n : 0.0;
  return s;
}

// The four-station figures of these clips before foot trackers existed (the same build of
// the solver, simulator and metrics): the six-station support changes nothing for them.
// (Re-pinned when the station filter's corrections became minimum-jerk over two reading
// intervals; the foot support was not touched.)
struct Before {
  const char* clip;
  double upper_m, all_m;
  bool walking;  // the legs move (CMU); else a standing gesture clip
};
constexpr Before kBefore[] = {
    {"mocap/cmu/01_01.bvh", 0.022140344524, 0.044243328249, true},
    {"mocap/gestures/dataset-1_call_normal_001.bvh", 0.005716440182, 0.008097216539, false},
};

TEST(FootTrackers, FourStationsUnchangedAndSixFollowTheLegs) {
  for (const Before& before : kBefore) {
    VISTEL_REQUIRE_SHARED(path, before.clip);
    auto body = loadClipBody(path);
    ASSERT_TRUE(body.ok()) << body.error().message;
    const Score four = scoreClip(*body, false);
    EXPECT_NEAR(four.m.mpjpe_upper_m, before.upper_m, 1e-9) << before.clip;
    EXPECT_NEAR(four.m.mpjpe_all_m, before.all_m, 1e-9) << before.clip;
    const Score six = scoreClip(*body, true);
    std::printf(
        "%s: legs %.2f -> %.2f cm, feet %.2f -> %.2f cm, all %.2f -> %.2f cm, upper "
        "%.2f -> %.2f cm\n",
        before.clip, four.m.mpjpe_legs_m * 100, six.m.mpjpe_legs_m * 100, four.feet_m * 100,
        six.feet_m * 100, four.m.mpjpe_all_m * 100, six.m.mpjpe_all_m * 100,
        four.m.mpjpe_upper_m * 100, six.m.mpjpe_upper_m * 100);
    if (before.walking) {
      // Walking: the standing heuristic cannot follow the legs; the foot sensors can.
      EXPECT_LT(six.m.mpjpe_legs_m, 0.5 * four.m.mpjpe_legs_m) << before.clip;
      EXPECT_LT(six.m.mpjpe_all_m, 0.75 * four.m.mpjpe_all_m) << before.clip;
    } else {
      // Standing still: the heuristic's planted feet are close already and the legs' error is
      // the hips' (from the chest): the feet get closer, the legs no worse.
      EXPECT_LT(six.feet_m, 0.6 * four.feet_m) << before.clip;
      EXPECT_LT(six.m.mpjpe_legs_m, 1.02 * four.m.mpjpe_legs_m) << before.clip;
    }
    EXPECT_LT(six.m.mpjpe_upper_m, 1.1 * four.m.mpjpe_upper_m) << before.clip;
  }
}

// End to end: the simulated rig with six stations (config/sensors/sim_feet.toml) solved onto
// an avatar, recorded (format version 2, the feet in every frame) and replayed through the
// same solver: the same postures.
TEST(FootTrackers, SixStationSessionRecordsAndReplays) {
  VISTEL_REQUIRE_SHARED(clip, "mocap/gestures/dataset-1_call_normal_001.bvh");
  const Skeleton avatar = test::makeHumanoid(false);
  const std::string recording = test::scratchDir() + "/call_feet.vrec";
  PostureSourceOptions options;
  options.realtime = false;
  options.record_path = recording;
  options.config_path = "config/sensors/sim_feet.toml";
  auto live = openPostureSource("sim:" + clip, avatar, options);
  ASSERT_TRUE(live.ok()) << live.error().message;
  std::vector<Posture> after_calibration;
  std::size_t frames = 0, first_calibrated = 0;
  Posture p;
  while (frames < 300) {
    ASSERT_TRUE((*live)->poll(0.1, p).isFrame());
    ++frames;
    if ((*live)->calibrated()) {
      if (after_calibration.empty()) first_calibrated = frames;
      after_calibration.push_back(p);
    }
  }
  ASSERT_GT(first_calibrated, 0u);
  EXPECT_TRUE((*live)->lastFrame().station(BodySite::kLeftFoot).valid);
  (*live)->stopRecording();
  auto rec = loadRecording(recording);
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  ASSERT_EQ(rec->frames.size(), frames);
  EXPECT_TRUE(rec->frames.back().station(BodySite::kRightFoot).valid);
  test::expectReplayMatches(recording, avatar, after_calibration, first_calibrated, frames);
}

// A bit-exact check (run by hand: --gtest_also_run_disabled_tests): the FNV-1a hash of every
// solved posture of four-station solves, to compare between builds of the same compiler.
TEST(FootTrackers, DISABLED_PrintFourStationFingerprints) {
  for (const Before& before : kBefore) {
    VISTEL_REQUIRE_SHARED(path, before.clip);
    auto body = loadClipBody(path);
    ASSERT_TRUE(body.ok());
    for (int noise = 0; noise < 2; ++noise) {
      for (int seated = 0; seated < 2; ++seated) {
        ClipSolveOptions options;
        if (!noise) options.sim = noiselessSimOptions();
        if (seated) options.solver.stance = Stance::kSeated;
        auto solved = solveClip(*body, options);
        ASSERT_TRUE(solved.ok());
        std::uint64_t h = kFnvOffset;
        for (const Posture& p : solved->postures) {
          h = hashSpan(std::span<const glm::quat>(p.rotations), h);
          h = fnv1a64(&p.root_translation, sizeof p.root_translation, h);
          h = hashSpan(std::span<const glm::vec3>(p.translations), h);
        }
        const PostureMetrics m =
            measurePostures(body->skeleton, body->roles, clipPostures(body->clip), solved->postures,
                            body->clip.frame_time);
        std::printf("FP %s noise=%d seated=%d hash=%016llx upper=%.12f all=%.12f\n", before.clip,
                    noise, seated, static_cast<unsigned long long>(h), m.mpjpe_upper_m,
                    m.mpjpe_all_m);
      }
    }
  }
}

}  // namespace
}  // namespace vistel
