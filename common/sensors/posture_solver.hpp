// PostureSolver: four 6-DOF stations (six with foot trackers) and two gloves -> a Posture
// on a skeleton (DESIGN.md §5). Works on any skeleton through its JointRoles (a clip's or an
// avatar's).
//
// Per frame, in model space (metres, +Y up):
//  - stations: filtered in sensor space before the solve and predicted forward to the frame
//    time (covers latency and a shared update rate): by default a Kalman filter per station
//    (station_filter.hpp: noise model from the sensors config, corners per station, each
//    reading's correction eased in so a 30 Hz reading makes no step in a 120 Hz output;
//    the position filtered at the joint its segment turns about, e.g. the elbow), or the
//    One-Euro filter (Casiez et al. 2012) with velocity prediction; a station that
//    drops out or goes stale is held (a short fading extrapolation, then still) and, when it
//    returns, blended back over blend_back_s instead of jumping;
//  - trunk: the chest sensor's rotation since calibration is split into a pelvis part (yaw
//    that lazily follows the chest within a twist limit, plus a share of the bend) and the
//    rest, spread evenly over the spine joints up to the chest; the hips are placed so the
//    chest segment lands where its sensor says, then smoothed (the trunk prior: hips move
//    slowly, the trunk turns about them; hips_cutoff_hz) and the chest follows them;
//  - head: the head's rotation relative to the chest is spread over the neck joints;
//  - arms: the clavicle turns with the chest and lifts when the upper arm rises above
//    clavicle_lift_start_deg; each arm is an analytic two-bone IK from the shoulder to the
//    wrist the forearm sensor gives, with the swivel (the elbow's place on its circle) taken
//    from the forearm sensor's own axis; the upper arm's twist keeps the elbow a hinge; the
//    forearm takes the sensor's rotation; the hand adds the glove's wrist pitch/yaw;
//  - fingers: glove flexion and abduction angles, about axes from the calibration hand;
//  - legs: a leg whose foot station is worn (calibrated) and tracked is a two-bone IK from
//    the hip to the ankle the foot sensor gives, the knee bending about the foot's left-right
//    axis (the knee's hinge at calibration, fixed in the foot's frame: the ankle's flexion
//    leaves it alone; the swivel turns at most max_knee_swivel_deg_s and holds where that axis
//    lies along the leg, so it cannot flip the knee), the
//    foot taking the sensor's rotation; the stance does not matter then. Otherwise standing — feet
//    planted, re-planted under the hips after a step's distance or turn, two-bone IK with knees
//    forward; seated — thighs forward, shins down. Without foot stations the legs are
//    exactly what they were before foot trackers existed;
//  - joint limits: each driven joint stays within a cone (per role) around its calibration
//    rotation.
// solve() allocates nothing (once `out` has the skeleton's size) and never fails: missing
// stations leave their part of the body in the calibration posture, carried by the chest.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/sensors/body_roles.hpp"
#include "common/sensors/calibration.hpp"
#include "common/sensors/hand_model.hpp"
#include "common/sensors/one_euro.hpp"
#include "common/sensors/sensor_frame.hpp"
#include "common/sensors/station_filter.hpp"

namespace vistel {

enum class Stance : std::uint8_t { kStanding, kSeated };
// How stations are filtered: a Kalman filter tuned by the tracker's noise model
// (station_filter.hpp), or the One-Euro filter with velocity prediction (one_euro.hpp).
enum class StationFilterKind : std::uint8_t { kKalman, kOneEuro };

// The Kalman settings (chosen by bench_posture sweeps over the shared gesture clips, with
// CMU 131_01 in view; no clip was held out, so they may fit these clips): rotations at a 4 Hz
// corner; the wrists' positions (filtered at the elbow, see StationFilterParams::pivot) at 2 Hz
// rising by 5 Hz per m/s of their speed; the head's position at 2 Hz; the chest (which carries the
// trunk, and the hips and legs through lever arms) at 1.5 Hz, its position's corner rising by 5 Hz
// per m/s.
inline std::array<StationFilterParams, kBodySiteCount> defaultStationFilters() {
  std::array<StationFilterParams, kBodySiteCount> f{};
  f[static_cast<std::size_t>(BodySite::kHead)].position_cutoff_hz = 2.0f;
  for (BodySite wrist : {BodySite::kLeftWrist, BodySite::kRightWrist}) {
    f[static_cast<std::size_t>(wrist)].position_cutoff_hz = 2.0f;
    f[static_cast<std::size_t>(wrist)].position_beta = 5.0f;
  }
  StationFilterParams& chest = f[static_cast<std::size_t>(BodySite::kChest)];
  chest.position_cutoff_hz = 1.5f;
  chest.orientation_cutoff_hz = 1.5f;
  chest.position_beta = 5.0f;
  // Feet (filtered at the ankle): still while planted, fast in a step: 1 Hz rising by 20 Hz per
  // m/s (a planted foot's noise reaches the knee of a nearly straight leg many times over), and
  // the output one reading interval behind the asked time (25 ms at the 40 Hz a foot gets when
  // six stations share 240 Hz), so the foot is interpolated between its readings rather than
  // extrapolated past the newest. A kick's foot reverses at 3-5 m/s; extrapolated over a
  // reading's age it overshot by 10-25 cm and came back (CMU 131 clips, bench_posture
  // /sensors:6: largest jump 1.6-2.4x the clip's, 1.1-1.4x with the delay; legs MPJPE and the
  // jitter a little lower, on the gesture clips too, than at 1 Hz + 10 Hz per m/s undelayed).
  for (BodySite foot : {BodySite::kLeftFoot, BodySite::kRightFoot}) {
    f[static_cast<std::size_t>(foot)].position_cutoff_hz = 1.0f;
    f[static_cast<std::size_t>(foot)].position_beta = 20.0f;
    f[static_cast<std::size_t>(foot)].delay_intervals = 1.0;
  }
  return f;
}

struct SolverOptions {
  Stance stance = Stance::kStanding;
  bool filter = true;  // false: every station's latest reading as it is
  StationFilterKind filter_kind = StationFilterKind::kKalman;
  // kKalman: noise model, corners and easing per station (indexed by BodySite); see
  // defaultStationFilters().
  std::array<StationFilterParams, kBodySiteCount> station_filters = defaultStationFilters();
  // beta: Hz per m/s (positions) or per rad/s (rotations). Prediction trades lag against
  // jitter: its velocity is low-passed at predict_cutoff_hz (bench_posture measures both).
  OneEuroParams position_filter{1.0f, 15.0f, 1.0f, 2.0f};
  OneEuroParams orientation_filter{1.0f, 3.0f, 1.0f, 2.0f};
  bool predict = true;
  double max_predict_s = 0.05;   // never extrapolate a reading further than this
  double stale_after_s = 0.15;   // a reading older than this counts as a dropout
  double hold_predict_s = 0.08;  // fading extrapolation while a station is out
  double blend_back_s = 0.3;     // blend from the held pose back onto a returning station
  // The trunk's prior: the hips' position (from the chest sensor and the trunk's rotation)
  // smoothed at this corner, rising by hips_beta Hz per m/s of their speed; 0: off.
  float hips_cutoff_hz = 1.0f;
  float hips_beta = 15.0f;
  float pelvis_tilt_share = 0.4f;         // share of the trunk's bend the pelvis takes
  float pelvis_twist_limit_deg = 30.0f;   // most the spine twists before the pelvis turns
  double pelvis_follow_s = 1.0;           // time constant of the pelvis following the chest
  float clavicle_lift_start_deg = 70.0f;  // upper-arm elevation where the clavicle lifts
  float clavicle_lift_gain = 0.3f;        // clavicle degrees per degree above the start
  float clavicle_lift_max_deg = 25.0f;
  bool joint_limits = true;
  bool fingers = true;
  float step_distance_m = 0.25f;  // standing: re-plant a foot when its target moves this far
  float step_turn_deg = 35.0f;    // ... or the pelvis turns this far
  double step_time_s = 0.3;
  // Foot trackers: the most the knee's swivel about the hip-ankle line turns per second (the
  // swivel comes from the foot's left-right axis, ill-defined where that lies along the line:
  // no flips). 720 did a little better than 180-360 and as well as 1500 on the CMU 131 clips
  // (legs MPJPE, jitter, jump).
  float max_knee_swivel_deg_s = 720.0f;
};

class PostureSolver {
 public:
  // Precomputes everything from the skeleton and the calibration (allocates). Fails when
  // the calibration's posture does not fit the skeleton or the options are out of range.
  static Result<PostureSolver> create(const Skeleton& skeleton, const JointRoles& roles,
                                      BodyCalibration calibration, SolverOptions options);

  // The posture for a frame (see the file comment); `out` is resized on first use only.
  void solve(const SensorFrame& frame, Posture& out);
  // Forgets filters, held stations and the feet (the next frame starts afresh).
  void reset();

  // Bit (1 << site) set for every station currently held (dropped out or stale); a station
  // not worn (a foot station that was not calibrated) is never held.
  unsigned heldStations() const;
  // True when the side's (0 left, 1 right) foot station is worn: calibrated, and the
  // skeleton has that leg.
  bool footTracked(int side) const { return foot_worn_[static_cast<std::size_t>(side)]; }
  const Skeleton& skeleton() const { return skeleton_; }
  const JointRoles& roles() const { return roles_; }
  const BodyCalibration& calibration() const { return calibration_; }
  const SolverOptions& options() const { return options_; }

 private:
  struct Track {
    OneEuroVec3 position;
    OneEuroQuat rotation;
    StationFilter kalman;
    double sample_time = 0.0;
    bool seen = false;
    bool lost = false;
    double lost_at = 0.0;
    glm::vec3 lost_p{0.0f};
    glm::quat lost_q{1.0f, 0.0f, 0.0f, 0.0f};
    glm::vec3 hold_v{0.0f};
    glm::vec3 hold_w{0.0f};
    bool blending = false;
    double blend_t0 = 0.0;
    glm::vec3 blend_dp{0.0f};
    glm::quat blend_dq{1.0f, 0.0f, 0.0f, 0.0f};
    glm::vec3 out_p{0.0f};  // last output, tracker space
    glm::quat out_q{1.0f, 0.0f, 0.0f, 0.0f};
  };
  struct Finger {
    std::array<int, 3> joint{-1, -1, -1};
    std::array<int, 3> sensor{-1, -1, -1};  // flexion GloveSensor per segment
    glm::vec3 flex_axis{1.0f, 0.0f, 0.0f};  // model space at calibration
    glm::vec3 spread_axis{0.0f, 1.0f, 0.0f};
    int spread_sensor_a = -1;  // spread = sign * (a + b)
    int spread_sensor_b = -1;
    float spread_sign = 0.0f;
    glm::vec3 roll_axis{0.0f};  // thumb: roll across the palm at its base
  };
  struct Arm {
    int clavicle = -1, upperarm = -1, forearm = -1, hand = -1;
    float upper_len = 0.0f, fore_len = 0.0f;
    glm::vec3 hand_offset{0.0f};                    // forearm frame: forearm joint -> hand joint
    glm::vec3 forearm_axis{0.0f};                   // forearm frame, unit
    glm::vec3 upper_dir_c{0.0f};                    // calibration, model space
    glm::vec3 hinge_c{0.0f};                        // calibration elbow hinge axis, model space
    glm::quat frame_c_inv{1.0f, 0.0f, 0.0f, 0.0f};  // inverse of the calibration IK frame
    float lift_c = 0.0f;  // clavicle lift at the calibration posture, radians
    WristModel wrist;
    std::array<Finger, 5> fingers;
    // per frame state
    glm::vec3 hinge{0.0f};
  };
  struct Leg {
    int thigh = -1, shin = -1, foot = -1;
    float upper_len = 0.0f, lower_len = 0.0f;
    glm::quat frame_c_inv{1.0f, 0.0f, 0.0f, 0.0f};  // thigh IK frame at calibration
    glm::quat shin_frame_c_inv{1.0f, 0.0f, 0.0f, 0.0f};
    glm::vec3 foot_from_hips_c{0.0f};  // calibration, model space
    // With a foot station: the knee's hinge axis in the foot's frame, and the IK frames at
    // calibration built with it.
    glm::vec3 hinge_foot{1.0f, 0.0f, 0.0f};
    glm::quat tracked_frame_c_inv{1.0f, 0.0f, 0.0f, 0.0f};
    glm::quat tracked_shin_frame_c_inv{1.0f, 0.0f, 0.0f, 0.0f};
    glm::vec3 swivel{0.0f};  // last frame's knee side (unit, across the hip-ankle line)
    bool swivel_init = false;
    // per frame state
    bool planted = false;
    glm::vec3 foot_pos{0.0f};  // planted foot, model space
    float foot_yaw = 0.0f;
    bool stepping = false;
    double step_t0 = 0.0;
    glm::vec3 step_from{0.0f};
  };

  PostureSolver() = default;
  bool trackStation(int site, const SensorFrame& frame, glm::vec3& p, glm::quat& q);
  void propagate(const glm::vec3& hips_position);
  void solveArm(int side, const SensorFrame& frame, bool wrist_available,
                const glm::quat& w_forearm, const glm::vec3& p_forearm,
                const glm::quat& chest_delta);
  void solveFingers(int side, const GloveReading& glove, const glm::quat& hand_delta);
  void solveLeg(int side, double now, const glm::quat& pelvis_yaw, const glm::vec3& hips_position);
  void solveTrackedLeg(int side, float dt, const glm::quat& w_foot, const glm::vec3& p_ankle);
  void compose(const glm::vec3& hips_position, Posture& out);

  Skeleton skeleton_;
  JointRoles roles_{};
  BodyCalibration calibration_;
  SolverOptions options_;
  int n_ = 0;
  int hips_ = -1;
  int chest_ = -1;
  int head_ = -1;
  std::vector<int> trunk_path_;       // hips (excl.) .. chest segment (incl.), top-down
  std::vector<int> neck_path_;        // chest segment (excl.) .. head (incl.)
  std::vector<glm::quat> local_c_;    // (njoint) calibration local rotations
  std::vector<glm::quat> world_c_;    // (njoint) calibration world rotations
  std::vector<glm::vec3> pos_c_;      // (njoint) calibration positions
  std::vector<glm::vec3> offset_;     // (njoint) joint origin in the parent's frame
  std::vector<std::uint8_t> driven_;  // (njoint) 1 when the solver sets the world rotation
  std::vector<float> limit_;          // (njoint) cone limit, radians (0 = none)
  BodyFrame body_c_;
  std::array<Arm, 2> arms_;
  std::array<Leg, 2> legs_;
  std::array<StationCalibration, kBodySiteCount> stations_{};
  std::array<glm::vec3, kBodySiteCount> pivot_{};  // sensor -> segment joint, sensor frame
  std::array<bool, kBodySiteCount> worn_{};        // upper body: always; feet: calibrated
  std::array<bool, 2> foot_worn_{};

  // Per-frame state.
  std::array<Track, kBodySiteCount> tracks_{};
  std::vector<glm::quat> world_;  // (njoint)
  std::vector<glm::vec3> pos_;    // (njoint)
  bool first_ = true;
  double last_time_ = 0.0;
  float chest_yaw_ = 0.0f;  // unwrapped
  float prev_yaw_raw_ = 0.0f;
  float pelvis_yaw_ = 0.0f;
  Kalman3 hips_kf_;
  bool hips_init_ = false;
  double hips_speed_ = 0.0;
};

}  // namespace vistel
