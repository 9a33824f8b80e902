#include "common/sensors/posture_solver.hpp"

#include <algorithm>
#include <cmath>

#include "common/sensors/rotation_utils.hpp"

namespace vistel {
namespace {

const glm::vec3 kUp(0.0f, 1.0f, 0.0f);
constexpr glm::quat kIdentity(1.0f, 0.0f, 0.0f, 0.0f);

float smoothstep(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

float wrapPi(float a) {
  while (a > glm::pi<float>()) a -= glm::two_pi<float>();
  while (a <= -glm::pi<float>()) a += glm::two_pi<float>();
  return a;
}

// Rotation taking the orthonormal frame (a, b) to itself expressed as a quaternion.
glm::quat frameQuat(const glm::vec3& a, const glm::vec3& b) {
  return glm::normalize(glm::quat_cast(frameFrom(a, b)));
}

// The elbow (knee) of a two-bone chain from `root` with bone lengths l1, l2 reaching for
// `target`, on the side of `pole_dir` (a direction hint). Writes the joint positions;
// an unreachable target is approached along the root->target line.
void twoBoneIk(const glm::vec3& root, float l1, float l2, const glm::vec3& target,
               const glm::vec3& pole_dir, glm::vec3& mid, glm::vec3& end) {
  glm::vec3 axis = target - root;
  float d = glm::length(axis);
  axis = d > 1e-6f ? axis / d : glm::vec3(0.0f, -1.0f, 0.0f);
  d = std::clamp(d, std::abs(l1 - l2) + 1e-5f, l1 + l2);
  const float a = (l1 * l1 - l2 * l2 + d * d) / (2.0f * d);
  const float r = std::sqrt(std::max(0.0f, l1 * l1 - a * a));
  glm::vec3 v = pole_dir - axis * glm::dot(pole_dir, axis);
  const float vl = glm::length(v);
  v = vl > 1e-6f ? v / vl : anyPerpendicular(axis);
  mid = root + axis * a + v * r;
  end = root + axis * d;
}

float liftFor(float elevation, const SolverOptions& o) {
  const float start = glm::radians(o.clavicle_lift_start_deg);
  return std::min(glm::radians(o.clavicle_lift_max_deg),
                  std::max(0.0f, elevation - start) * o.clavicle_lift_gain);
}

// A rotation pulled back into a cone of `limit` radians around `center`.
glm::quat limitRotation(const glm::quat& q, const glm::quat& center, float limit) {
  const glm::quat delta = normalizeSafe(glm::inverse(center) * q);
  const glm::vec3 r = rotationVector(delta);
  const float angle = glm::length(r);
  if (angle <= limit) return q;
  return glm::normalize(center * fromRotationVector(r * (limit / angle)));
}

}  // namespace

Result<PostureSolver> PostureSolver::create(const Skeleton& skeleton, const JointRoles& roles,
                                            BodyCalibration calibration, SolverOptions options) {
  const int n = skeleton.jointCount();
  if (n == 0) return fail("posture solver: empty skeleton");
  if (calibration.posture.rotations.size() != static_cast<std::size_t>(n)) {
    return fail("posture solver: calibration posture has {} rotations for {} joints",
                calibration.posture.rotations.size(), n);
  }
  if (!calibration.posture.translations.empty() &&
      calibration.posture.translations.size() != static_cast<std::size_t>(n)) {
    return fail("posture solver: calibration posture has {} translations for {} joints",
                calibration.posture.translations.size(), n);
  }
  if (!(options.position_filter.min_cutoff_hz > 0.0f) ||
      !(options.orientation_filter.min_cutoff_hz > 0.0f) ||
      !(options.position_filter.d_cutoff_hz > 0.0f) ||
      !(options.orientation_filter.d_cutoff_hz > 0.0f) || options.position_filter.beta < 0.0f ||
      options.orientation_filter.beta < 0.0f) {
    return fail("posture solver: filter cutoffs must be positive and betas non-negative");
  }
  if (!(options.pelvis_tilt_share >= 0.0f && options.pelvis_tilt_share <= 1.0f)) {
    return fail("posture solver: pelvis_tilt_share {} outside [0, 1]", options.pelvis_tilt_share);
  }
  if (!(options.pelvis_follow_s > 0.0) || !(options.step_time_s > 0.0) ||
      !(options.blend_back_s > 0.0) || !(options.stale_after_s > 0.0)) {
    return fail("posture solver: time constants must be positive");
  }
  if (!(options.max_knee_swivel_deg_s > 0.0f)) {
    return fail("posture solver: max_knee_swivel_deg_s {} must be positive",
                options.max_knee_swivel_deg_s);
  }

  PostureSolver s;
  s.skeleton_ = skeleton;
  s.roles_ = roles;
  s.calibration_ = std::move(calibration);
  s.options_ = options;
  s.n_ = n;
  s.hips_ = roles[Role::kHips];
  s.chest_ = roles.chestSegment();
  s.head_ = roles[Role::kHead];
  s.stations_ = s.calibration_.stations;
  for (int st = 0; st < kBodySiteCount; ++st) {
    if (!s.stations_[st].calibrated) {
      s.stations_[st].segment = mountSegment(roles, static_cast<BodySite>(st));
    }
  }

  // The calibration posture's joints.
  const std::size_t nn = static_cast<std::size_t>(n);
  std::vector<glm::mat4> model(nn);
  poseSkeleton(s.skeleton_, s.calibration_.posture, model);
  s.local_c_ = s.calibration_.posture.rotations;
  for (glm::quat& q : s.local_c_) q = normalizeSafe(q);
  s.world_c_.resize(nn);
  s.pos_c_.resize(nn);
  s.offset_.resize(nn);
  for (std::size_t j = 0; j < nn; ++j) {
    s.world_c_[j] = worldRotation(model[j]);
    s.pos_c_[j] = glm::vec3(model[j][3]);
  }
  for (std::size_t j = 1; j < nn; ++j) {
    const std::size_t p = static_cast<std::size_t>(s.skeleton_.parents[j]);
    s.offset_[j] = glm::inverse(s.world_c_[p]) * (s.pos_c_[j] - s.pos_c_[p]);
  }
  s.body_c_ = bodyFrameAt(roles, s.pos_c_);

  // Paths: hips -> chest segment, chest segment -> head.
  for (int j = s.chest_; j != s.hips_; j = s.skeleton_.parents[static_cast<std::size_t>(j)]) {
    s.trunk_path_.insert(s.trunk_path_.begin(), j);
  }
  for (int j = s.head_; j != s.chest_; j = s.skeleton_.parents[static_cast<std::size_t>(j)]) {
    s.neck_path_.insert(s.neck_path_.begin(), j);
  }

  // Which joints the solver drives, and their limits.
  s.driven_.assign(nn, 0);
  s.limit_.assign(nn, 0.0f);
  auto drive = [&](int j, float limit_deg) {
    if (j < 0) return;
    s.driven_[static_cast<std::size_t>(j)] = 1;
    s.limit_[static_cast<std::size_t>(j)] = glm::radians(limit_deg);
  };
  drive(s.hips_, 0.0f);
  for (int j : s.trunk_path_) drive(j, 50.0f);
  for (int j : s.neck_path_) drive(j, j == s.head_ ? 75.0f : 60.0f);

  for (int side = 0; side < 2; ++side) {
    Arm& arm = s.arms_[static_cast<std::size_t>(side)];
    arm.clavicle = roles[clavicleRole(side)];
    arm.upperarm = roles[upperarmRole(side)];
    arm.forearm = roles[forearmRole(side)];
    arm.hand = roles[handRole(side)];
    if (arm.clavicle >= 0 && !isAncestor(s.skeleton_, arm.clavicle, arm.upperarm))
      arm.clavicle = -1;
    drive(arm.clavicle, 35.0f);
    drive(arm.upperarm, 0.0f);
    drive(arm.forearm, 0.0f);
    drive(arm.hand, 95.0f);
    const glm::vec3 ps = s.pos_c_[static_cast<std::size_t>(arm.upperarm)];
    const glm::vec3 pe = s.pos_c_[static_cast<std::size_t>(arm.forearm)];
    const glm::vec3 pw = s.pos_c_[static_cast<std::size_t>(arm.hand)];
    arm.upper_len = glm::distance(ps, pe);
    arm.fore_len = glm::distance(pe, pw);
    if (arm.upper_len < 1e-4f || arm.fore_len < 1e-4f) {
      return fail("posture solver: {} arm has a zero-length bone", side == 0 ? "left" : "right");
    }
    const glm::quat wf = s.world_c_[static_cast<std::size_t>(arm.forearm)];
    arm.hand_offset = glm::inverse(wf) * (pw - pe);
    arm.forearm_axis = glm::normalize(arm.hand_offset);
    arm.upper_dir_c = glm::normalize(pe - ps);
    const glm::vec3 fore_dir = glm::normalize(pw - pe);
    const glm::vec3 bent = glm::cross(arm.upper_dir_c, fore_dir);
    glm::vec3 straight = glm::cross(arm.upper_dir_c, s.body_c_.forward);
    if (glm::length(straight) < 1e-3f) straight = anyPerpendicular(arm.upper_dir_c);
    straight = glm::normalize(straight);
    const float w =
        smoothstep(std::sin(glm::radians(8.0f)), std::sin(glm::radians(20.0f)), glm::length(bent));
    glm::vec3 hinge =
        glm::length(bent) > 1e-6f ? glm::mix(straight, glm::normalize(bent), w) : straight;
    hinge -= arm.upper_dir_c * glm::dot(hinge, arm.upper_dir_c);
    arm.hinge_c = glm::normalize(hinge);
    arm.frame_c_inv = glm::inverse(frameQuat(arm.upper_dir_c, arm.hinge_c));
    const float elevation = std::acos(std::clamp(glm::dot(arm.upper_dir_c, -kUp), -1.0f, 1.0f));
    arm.lift_c = liftFor(elevation, s.options_);
    arm.wrist = makeWristModel(side, s.body_c_, wf, s.world_c_[static_cast<std::size_t>(arm.hand)],
                               arm.forearm_axis);

    // Fingers: axes from the calibration hand (middle or index knuckle, index and pinky).
    const glm::vec3 ph = pw;
    auto pos = [&](Role r) { return s.pos_c_[static_cast<std::size_t>(roles[r])]; };
    glm::vec3 along(0.0f);
    if (roles.has(fingerRole(side, 2, 0))) {
      along = pos(fingerRole(side, 2, 0)) - ph;
    } else if (roles.has(fingerRole(side, 1, 0))) {
      along = pos(fingerRole(side, 1, 0)) - ph;
    }
    along = glm::length(along) > 1e-5f ? glm::normalize(along) : fore_dir;
    glm::vec3 lateral = s.body_c_.forward;  // the thumb side in the calibration posture
    if (roles.has(fingerRole(side, 1, 0)) && roles.has(fingerRole(side, 4, 0))) {
      lateral = pos(fingerRole(side, 1, 0)) - pos(fingerRole(side, 4, 0));
    }
    lateral -= along * glm::dot(lateral, along);
    lateral = glm::length(lateral) > 1e-5f ? glm::normalize(lateral) : anyPerpendicular(along);
    const glm::vec3 palm = (side == 0 ? 1.0f : -1.0f) * glm::cross(along, lateral);
    const glm::vec3 flex = glm::normalize(glm::cross(along, palm));
    const glm::vec3 spread = glm::normalize(glm::cross(along, lateral));
    static constexpr int kFlexSensors[5][3] = {{-1, kThumbMpj, kThumbIj},
                                               {kIndexMpj, kIndexPij, kIndexDij},
                                               {kMiddleMpj, kMiddlePij, kMiddleDij},
                                               {kRingMpj, kRingPij, kRingDij},
                                               {kPinkyMpj, kPinkyPij, kPinkyDij}};
    for (int f = 0; f < 5; ++f) {
      Finger& finger = arm.fingers[static_cast<std::size_t>(f)];
      for (int k = 0; k < 3; ++k) {
        finger.joint[static_cast<std::size_t>(k)] = roles[fingerRole(side, f, k)];
        finger.sensor[static_cast<std::size_t>(k)] = kFlexSensors[f][k];
        if (s.options_.fingers) drive(finger.joint[static_cast<std::size_t>(k)], 120.0f);
      }
      finger.flex_axis = flex;
      finger.spread_axis = spread;
      if (f == 0) {
        // The thumb curls across the palm about its own axis; abduction lifts it off the
        // index; the rotation sensor rolls it about the hand's long axis.
        glm::vec3 thumb_dir = lateral;
        if (roles.has(fingerRole(side, 0, 0)) && roles.has(fingerRole(side, 0, 1))) {
          thumb_dir = pos(fingerRole(side, 0, 1)) - pos(fingerRole(side, 0, 0));
        }
        thumb_dir = glm::length(thumb_dir) > 1e-5f ? glm::normalize(thumb_dir) : lateral;
        glm::vec3 tflex = glm::cross(thumb_dir, palm);
        finger.flex_axis = glm::length(tflex) > 1e-4f ? glm::normalize(tflex) : flex;
        finger.spread_axis = spread;
        finger.spread_sensor_a = kThumbAbduction;
        finger.spread_sign = 1.0f;
        finger.roll_axis = along;
      } else if (f == 1) {
        finger.spread_sensor_a = kMiddleIndexAbduction;
        finger.spread_sign = 1.0f;
      } else if (f == 3) {
        finger.spread_sensor_a = kRingMiddleAbduction;
        finger.spread_sign = -1.0f;
      } else if (f == 4) {
        finger.spread_sensor_a = kRingMiddleAbduction;
        finger.spread_sensor_b = kPinkyRingAbduction;
        finger.spread_sign = -1.0f;
      }
    }
  }

  for (int side = 0; side < 2; ++side) {
    Leg& leg = s.legs_[static_cast<std::size_t>(side)];
    leg.thigh = roles[thighRole(side)];
    leg.shin = roles[shinRole(side)];
    leg.foot = roles[footRole(side)];
    if (leg.thigh < 0 || leg.shin < 0 || leg.foot < 0 ||
        !isAncestor(s.skeleton_, s.hips_, leg.thigh) ||
        !isAncestor(s.skeleton_, leg.thigh, leg.shin) ||
        !isAncestor(s.skeleton_, leg.shin, leg.foot)) {
      leg.thigh = leg.shin = leg.foot = -1;  // no legs to drive: they follow the hips
      continue;
    }
    const glm::vec3 pt = s.pos_c_[static_cast<std::size_t>(leg.thigh)];
    const glm::vec3 pk = s.pos_c_[static_cast<std::size_t>(leg.shin)];
    const glm::vec3 pf = s.pos_c_[static_cast<std::size_t>(leg.foot)];
    leg.upper_len = glm::distance(pt, pk);
    leg.lower_len = glm::distance(pk, pf);
    if (leg.upper_len < 1e-4f || leg.lower_len < 1e-4f) {
      leg.thigh = leg.shin = leg.foot = -1;
      continue;
    }
    drive(leg.thigh, 0.0f);
    drive(leg.shin, 0.0f);
    drive(leg.foot, 60.0f);
    // The knee hinge is the body's left-right axis.
    const glm::vec3 left = s.body_c_.left;
    const glm::vec3 d1 = glm::normalize(pk - pt);
    const glm::vec3 d2 = glm::normalize(pf - pk);
    leg.frame_c_inv = glm::inverse(frameQuat(d1, left));
    leg.shin_frame_c_inv = glm::inverse(frameQuat(d2, left));
    leg.foot_from_hips_c = pf - s.pos_c_[static_cast<std::size_t>(s.hips_)];
    // With a foot station: the knee's hinge axis, kept in the foot's frame (the ankle flexes
    // about much the same axis as the knee, so the foot's pitch leaves it alone): from the
    // calibration knee when it is bent (forward) enough to say, else across the knee's
    // forward side (forward and a little up, as the heuristic's).
    const glm::vec3 axis = glm::normalize(pf - pt);
    const glm::vec3 perp = (pk - pt) - axis * glm::dot(pk - pt, axis);
    const glm::vec3 forward_pole = glm::normalize(s.body_c_.forward + kUp * 0.1f);
    const glm::vec3 pole =
        glm::length(perp) > 0.02f * leg.upper_len && glm::dot(perp, s.body_c_.forward) > 0.0f
            ? glm::normalize(perp)
            : forward_pole;
    glm::vec3 v = pole - axis * glm::dot(pole, axis);
    v = glm::length(v) > 1e-6f ? glm::normalize(v) : anyPerpendicular(axis);
    const glm::vec3 hinge = glm::normalize(glm::cross(v, axis));
    leg.hinge_foot = glm::inverse(s.world_c_[static_cast<std::size_t>(leg.foot)]) * hinge;
    leg.tracked_frame_c_inv = glm::inverse(frameQuat(d1, hinge));
    leg.tracked_shin_frame_c_inv = glm::inverse(frameQuat(d2, hinge));
  }

  // Which stations are worn: the four upper-body ones always (an uncalibrated one leaves its
  // part in the calibration posture), a foot one when calibrated and its leg is driven.
  for (int st = 0; st < kBodySiteCount; ++st) {
    const BodySite site = static_cast<BodySite>(st);
    s.worn_[static_cast<std::size_t>(st)] = !isFootSite(site);
  }
  for (int side = 0; side < 2; ++side) {
    const std::size_t f = static_cast<std::size_t>(footSite(side));
    const bool worn =
        s.stations_[f].calibrated && s.legs_[static_cast<std::size_t>(side)].thigh >= 0;
    s.worn_[f] = worn;
    s.foot_worn_[static_cast<std::size_t>(side)] = worn;
    // A tracked foot turns as its sensor says (no cone around the calibration rotation).
    if (worn)
      s.limit_[static_cast<std::size_t>(s.legs_[static_cast<std::size_t>(side)].foot)] = 0.0f;
  }

  // From each sensor to its segment's joint, sensor frame, tracker units.
  for (int st = 0; st < kBodySiteCount; ++st) {
    const StationCalibration& c = s.stations_[static_cast<std::size_t>(st)];
    const BodyProportions& pr = s.calibration_.proportions;
    const float scale = st == static_cast<int>(BodySite::kHead)         ? pr.torso
                        : st == static_cast<int>(BodySite::kLeftWrist)  ? pr.arm[0]
                        : st == static_cast<int>(BodySite::kRightWrist) ? pr.arm[1]
                        : isFootSite(static_cast<BodySite>(st))         ? pr.height
                                                                        : 1.0f;
    s.pivot_[static_cast<std::size_t>(st)] =
        c.calibrated ? -(c.sensor_to_segment * c.offset) * scale : glm::vec3(0.0f);
  }

  s.world_.resize(nn);
  s.pos_.resize(nn);
  s.reset();
  return s;
}

void PostureSolver::reset() {
  for (Track& t : tracks_) t = Track{};
  first_ = true;
  last_time_ = 0.0;
  chest_yaw_ = prev_yaw_raw_ = pelvis_yaw_ = 0.0f;
  hips_init_ = false;
  for (Leg& leg : legs_) {
    leg.planted = false;
    leg.stepping = false;
    leg.swivel_init = false;
  }
  for (int side = 0; side < 2; ++side) {
    arms_[static_cast<std::size_t>(side)].hinge = arms_[static_cast<std::size_t>(side)].hinge_c;
  }
}

unsigned PostureSolver::heldStations() const {
  unsigned bits = 0;
  for (int s = 0; s < kBodySiteCount; ++s) {
    if (tracks_[static_cast<std::size_t>(s)].lost) bits |= 1u << s;
  }
  return bits;
}

bool PostureSolver::trackStation(int site, const SensorFrame& frame, glm::vec3& p, glm::quat& q) {
  Track& tr = tracks_[static_cast<std::size_t>(site)];
  const StationReading& r = frame.stations[static_cast<std::size_t>(site)];
  const bool usable = r.valid && frame.time - r.time <= options_.stale_after_s;
  const bool fresh = usable && (!tr.seen || r.time > tr.sample_time);
  const OneEuroParams& pf = options_.position_filter;
  const OneEuroParams& qf = options_.orientation_filter;
  const bool kalman = options_.filter && options_.filter_kind == StationFilterKind::kKalman;
  const StationFilterParams& fp = options_.station_filters[static_cast<std::size_t>(site)];
  // The Kalman filter runs on a point of the segment (the pivot, sensor frame): the joint the
  // segment turns about moves least, so a rotation's prediction error swings less there.
  const glm::vec3 pivot = pivot_[static_cast<std::size_t>(site)] * fp.pivot;
  if (fresh) {
    if (tr.lost) {
      // Back after a dropout: restart the filters on the new reading and blend from the
      // held pose onto it.
      tr.position.reset();
      tr.rotation.reset();
      tr.position.update(r.position, 0.0f, pf);
      tr.rotation.update(r.orientation, 0.0f, qf);
      tr.kalman.reset();
      if (kalman)
        tr.kalman.update(r.position + r.orientation * pivot, r.orientation, r.time, frame.time, fp);
      tr.blending = true;
      tr.blend_t0 = frame.time;
      tr.blend_dp = tr.out_p - r.position;
      tr.blend_dq = normalizeSafe(tr.out_q * glm::inverse(r.orientation));
      tr.lost = false;
    } else {
      const float dt =
          tr.seen && options_.filter ? static_cast<float>(r.time - tr.sample_time) : 0.0f;
      if (kalman) {
        tr.kalman.update(r.position + r.orientation * pivot, r.orientation, r.time, frame.time, fp);
      } else {
        tr.position.update(r.position, dt, pf);
        tr.rotation.update(r.orientation, dt, qf);
      }
    }
    tr.sample_time = r.time;
    tr.seen = true;
  }
  if (!tr.seen) return false;
  if (!usable && !tr.lost) {
    tr.lost = true;
    tr.lost_at = frame.time;
    tr.lost_p = tr.out_p;
    tr.lost_q = tr.out_q;
    tr.hold_v = !options_.predict ? glm::vec3(0.0f)
                : kalman          ? tr.kalman.velocity()
                                  : tr.position.velocity();
    tr.hold_w = !options_.predict ? glm::vec3(0.0f)
                : kalman          ? tr.kalman.angularVelocity()
                                  : tr.rotation.angularVelocity();
    tr.blending = false;
  }
  if (tr.lost) {
    // Held: a fading extrapolation of the last motion, then still.
    const float th = static_cast<float>(options_.hold_predict_s);
    const float tau = static_cast<float>(frame.time - tr.lost_at);
    const float reach = th > 0.0f ? th * (1.0f - std::exp(-tau / th)) : 0.0f;
    p = tr.lost_p + tr.hold_v * reach;
    q = glm::normalize(fromRotationVector(tr.hold_w * reach) * tr.lost_q);
  } else if (kalman) {
    if (options_.predict) {
      tr.kalman.evaluate(frame.time, fp, p, q);
    } else {
      tr.kalman.current(p, q);
    }
    p -= q * pivot;
  } else {
    p = tr.position.value();
    q = tr.rotation.value();
    if (options_.predict) {
      // Forward over the filter's lag and the reading's age (bounded).
      const double age = std::max(0.0, frame.time - tr.sample_time);
      const float ahead_p =
          static_cast<float>(std::min(age + tr.position.lag(), options_.max_predict_s));
      const float ahead_q =
          static_cast<float>(std::min(age + tr.rotation.lag(), options_.max_predict_s));
      p += tr.position.velocity() * ahead_p;
      q = glm::normalize(fromRotationVector(tr.rotation.angularVelocity() * ahead_q) * q);
    }
  }
  if (!tr.lost) {
    if (tr.blending) {
      const float u = static_cast<float>((frame.time - tr.blend_t0) / options_.blend_back_s);
      if (u >= 1.0f) {
        tr.blending = false;
      } else {
        const float w = 1.0f - smoothstep(0.0f, 1.0f, u);
        p += tr.blend_dp * w;
        q = glm::normalize(fractionOf(tr.blend_dq, w) * q);
      }
    }
  }
  tr.out_p = p;
  tr.out_q = q;
  return true;
}

void PostureSolver::propagate(const glm::vec3& hips_position) {
  // World rotations of undriven joints follow their parents; positions from the root at the
  // origin, then shifted so the hips land where they belong.
  for (int j = 0; j < n_; ++j) {
    const std::size_t u = static_cast<std::size_t>(j);
    const int parent = skeleton_.parents[u];
    if (parent < 0) {
      if (!driven_[u]) world_[u] = local_c_[u];
      pos_[u] = glm::vec3(0.0f);
      continue;
    }
    const std::size_t pu = static_cast<std::size_t>(parent);
    if (!driven_[u]) world_[u] = world_[pu] * local_c_[u];
    pos_[u] = pos_[pu] + world_[pu] * offset_[u];
  }
  const glm::vec3 shift = hips_position - pos_[static_cast<std::size_t>(hips_)];
  for (glm::vec3& p : pos_) p += shift;
}

void PostureSolver::solveArm(int side, const SensorFrame& frame, bool wrist_available,
                             const glm::quat& w_forearm, const glm::vec3& p_forearm,
                             const glm::quat& chest_delta) {
  Arm& arm = arms_[static_cast<std::size_t>(side)];
  const std::size_t up = static_cast<std::size_t>(arm.upperarm);
  const std::size_t fo = static_cast<std::size_t>(arm.forearm);
  const std::size_t ha = static_cast<std::size_t>(arm.hand);
  if (!wrist_available) {
    world_[up] = chest_delta * world_c_[up];
    world_[fo] = chest_delta * world_c_[fo];
    world_[ha] = chest_delta * world_c_[ha];
    return;
  }
  // Two-bone IK from the shoulder to the wrist the sensor gives, the elbow on the side of the
  // sensor's elbow (the swivel). Near a straight arm the IK's elbow is ill-conditioned (a
  // millimetre of noise in the reach moves it by centimetres), so there the upper arm aims at
  // the sensor's elbow directly and the forearm keeps the sensor's axis. Both agree exactly
  // when the readings fit the bones.
  const glm::vec3 shoulder = pos_[up];
  const glm::vec3 wrist = p_forearm + w_forearm * arm.hand_offset;
  glm::vec3 elbow_ik, reached;
  twoBoneIk(shoulder, arm.upper_len, arm.fore_len, wrist, p_forearm - shoulder, elbow_ik, reached);
  glm::vec3 to_elbow = p_forearm - shoulder;
  to_elbow = glm::length(to_elbow) > 1e-6f ? glm::normalize(to_elbow)
                                           : glm::normalize(elbow_ik - shoulder);
  const glm::vec3 fore_axis = glm::normalize(wrist - p_forearm);
  const float sensor_bend = glm::length(glm::cross(to_elbow, fore_axis));
  const float w_ik =
      smoothstep(std::sin(glm::radians(5.0f)), std::sin(glm::radians(35.0f)), sensor_bend);
  const glm::vec3 elbow_direct = shoulder + to_elbow * arm.upper_len;
  const glm::vec3 elbow = glm::mix(elbow_direct, elbow_ik, w_ik);
  const glm::vec3 d1 = glm::normalize(elbow - shoulder);
  const glm::vec3 d2 =
      glm::normalize(glm::mix(fore_axis, glm::normalize(reached - elbow_ik), w_ik));

  // The elbow hinge: from the bend when bent, else carried over from the last frame.
  const glm::vec3 bent = glm::cross(d1, d2);
  const float sin_bend = glm::length(bent);
  glm::vec3 fallback = arm.hinge - d1 * glm::dot(arm.hinge, d1);
  if (glm::length(fallback) < 1e-4f)
    fallback = chest_delta * arm.hinge_c - d1 * glm::dot(chest_delta * arm.hinge_c, d1);
  if (glm::length(fallback) < 1e-4f) fallback = anyPerpendicular(d1);
  fallback = glm::normalize(fallback);
  const float w = smoothstep(std::sin(glm::radians(8.0f)), std::sin(glm::radians(20.0f)), sin_bend);
  glm::vec3 hinge = sin_bend > 1e-6f ? glm::mix(fallback, bent / sin_bend, w) : fallback;
  hinge -= d1 * glm::dot(hinge, d1);
  hinge = glm::length(hinge) > 1e-6f ? glm::normalize(hinge) : fallback;
  arm.hinge = hinge;

  world_[up] = glm::normalize(frameQuat(d1, hinge) * arm.frame_c_inv * world_c_[up]);
  // The forearm keeps the sensor's rotation, re-aimed along the IK's forearm.
  const glm::vec3 axis_now = w_forearm * arm.forearm_axis;
  world_[fo] = glm::normalize(rotationBetween(glm::normalize(axis_now), d2) * w_forearm);

  // The hand: the glove's wrist angles relative to calibration.
  const GloveReading& glove = frame.gloves[static_cast<std::size_t>(side)];
  const GloveReading& zero = calibration_.glove_zero[static_cast<std::size_t>(side)];
  if (glove.valid) {
    const float pitch = glove.angles[kWristPitch] - (zero.valid ? zero.angles[kWristPitch] : 0.0f);
    const float yaw = glove.angles[kWristYaw] - (zero.valid ? zero.angles[kWristYaw] : 0.0f);
    world_[ha] = handFromWrist(arm.wrist, world_[fo], pitch, yaw);
  } else {
    world_[ha] = glm::normalize(world_[fo] * arm.wrist.rest_relative);
  }
}

void PostureSolver::solveFingers(int side, const GloveReading& glove, const glm::quat& hand_delta) {
  Arm& arm = arms_[static_cast<std::size_t>(side)];
  for (const Finger& finger : arm.fingers) {
    float flex = 0.0f;
    float spread = 0.0f;
    float roll = 0.0f;
    if (glove.valid) {
      if (finger.spread_sensor_a >= 0)
        spread += glove.angles[static_cast<std::size_t>(finger.spread_sensor_a)];
      if (finger.spread_sensor_b >= 0)
        spread += glove.angles[static_cast<std::size_t>(finger.spread_sensor_b)];
      spread *= finger.spread_sign;
      if (glm::length(finger.roll_axis) > 0.5f) roll = glove.angles[kThumbRotation];
    }
    glm::quat base = glm::angleAxis(spread, finger.spread_axis);
    if (roll != 0.0f) base = glm::angleAxis(roll, finger.roll_axis) * base;
    for (int k = 0; k < 3; ++k) {
      const int sensor = finger.sensor[static_cast<std::size_t>(k)];
      if (glove.valid && sensor >= 0) flex += glove.angles[static_cast<std::size_t>(sensor)];
      const int j = finger.joint[static_cast<std::size_t>(k)];
      if (j < 0) continue;
      const std::size_t u = static_cast<std::size_t>(j);
      world_[u] =
          glm::normalize(hand_delta * base * glm::angleAxis(flex, finger.flex_axis) * world_c_[u]);
    }
  }
}

void PostureSolver::solveLeg(int side, double now, const glm::quat& pelvis_yaw,
                             const glm::vec3& hips_position) {
  Leg& leg = legs_[static_cast<std::size_t>(side)];
  if (leg.thigh < 0) return;
  const std::size_t th = static_cast<std::size_t>(leg.thigh);
  const std::size_t sh = static_cast<std::size_t>(leg.shin);
  const std::size_t ft = static_cast<std::size_t>(leg.foot);
  const glm::vec3 hip = pos_[th];
  const glm::vec3 fwd = pelvis_yaw * body_c_.forward;
  const float yaw = pelvis_yaw_;
  glm::vec3 target;
  float foot_yaw = yaw;
  if (options_.stance == Stance::kSeated) {
    // Thighs forward and level, shins straight down.
    target = hip + fwd * leg.upper_len - kUp * leg.lower_len;
  } else {
    // Standing: where the foot would rest under the hips; plant it, step when it drifts.
    glm::vec3 rest = pelvis_yaw * leg.foot_from_hips_c;
    rest.y = 0.0f;
    glm::vec3 wanted = hips_position + rest;
    wanted.y = pos_c_[ft].y;
    if (!leg.planted) {
      leg.foot_pos = wanted;
      leg.foot_yaw = yaw;
      leg.planted = true;
    }
    const bool drift = glm::distance(wanted, leg.foot_pos) > options_.step_distance_m ||
                       std::abs(yaw - leg.foot_yaw) > glm::radians(options_.step_turn_deg);
    if (drift && !leg.stepping) {
      leg.stepping = true;
      leg.step_t0 = now;
      leg.step_from = leg.foot_pos;
    }
    if (leg.stepping) {
      const float u = static_cast<float>((now - leg.step_t0) / options_.step_time_s);
      const float w = smoothstep(0.0f, 1.0f, u);
      leg.foot_pos = glm::mix(leg.step_from, wanted, w);
      if (u >= 1.0f) {
        leg.stepping = false;
        leg.foot_yaw = yaw;
      }
    }
    target = leg.foot_pos;
    foot_yaw = leg.stepping ? yaw : leg.foot_yaw;
  }
  // Soft reach: as the target nears full extension the knee straightens smoothly instead of
  // snapping (a straight chain's IK turns millimetres of hip noise into centimetres of knee).
  const float reach = leg.upper_len + leg.lower_len;
  const float soft = 0.0015f * reach;
  glm::vec3 to_target = target - hip;
  float d = glm::length(to_target);
  if (d > reach - soft && d > 1e-6f) {
    const float d_soft = reach - soft + soft * (1.0f - std::exp(-(d - (reach - soft)) / soft));
    to_target *= d_soft / d;
  }
  glm::vec3 knee, reached;
  twoBoneIk(hip, leg.upper_len, leg.lower_len, hip + to_target, fwd + kUp * 0.1f, knee, reached);
  const glm::vec3 d1 = (knee - hip) / leg.upper_len;
  const glm::vec3 d2 = glm::normalize(reached - knee);
  const glm::vec3 left = pelvis_yaw * body_c_.left;
  world_[th] = glm::normalize(frameQuat(d1, left) * leg.frame_c_inv * world_c_[th]);
  world_[sh] = glm::normalize(frameQuat(d2, left) * leg.shin_frame_c_inv * world_c_[sh]);
  world_[ft] = glm::normalize(glm::angleAxis(foot_yaw, kUp) * world_c_[ft]);
}

void PostureSolver::solveTrackedLeg(int side, float dt, const glm::quat& w_foot,
                                    const glm::vec3& p_ankle) {
  Leg& leg = legs_[static_cast<std::size_t>(side)];
  const std::size_t th = static_cast<std::size_t>(leg.thigh);
  const std::size_t sh = static_cast<std::size_t>(leg.shin);
  const std::size_t ft = static_cast<std::size_t>(leg.foot);
  const glm::vec3 hip = pos_[th];
  // Soft reach, as for the heuristic's legs: a straight leg's knee stays well conditioned.
  const float reach = leg.upper_len + leg.lower_len;
  const float soft = 0.0015f * reach;
  glm::vec3 to_target = p_ankle - hip;
  const float d = glm::length(to_target);
  if (d > reach - soft && d > 1e-6f) {
    const float d_soft = reach - soft + soft * (1.0f - std::exp(-(d - (reach - soft)) / soft));
    to_target *= d_soft / d;
  }
  // The knee's side (the swivel, the direction across the hip-ankle line): the knee bends
  // about the foot's own left-right axis (the knee's hinge at calibration, carried by the
  // foot). A direction kept in the foot's frame (where the toes point) would turn with the
  // ankle's flexion: a pointed or raised foot swung it through the hip-ankle line, 90-180
  // degrees off in the CMU 131 kicks and dance steps, and the knee popped across. The hinge
  // is ill-defined only where it lies along the hip-ankle line (the leg swung out sideways
  // with the foot across it): there the swivel holds the last frame's, and it never turns
  // faster than max_knee_swivel_deg_s.
  glm::vec3 axis = to_target;
  axis = glm::length(axis) > 1e-6f ? glm::normalize(axis) : -kUp;
  glm::vec3 v = glm::cross(axis, w_foot * leg.hinge_foot);
  const float across = glm::length(v);  // sine of the hinge's angle to the hip-ankle line
  v = across > 1e-6f ? v / across : anyPerpendicular(axis);
  if (leg.swivel_init) {
    glm::vec3 prev = leg.swivel - axis * glm::dot(leg.swivel, axis);
    if (glm::length(prev) > 1e-4f) {
      prev = glm::normalize(prev);
      float angle = std::atan2(glm::dot(glm::cross(prev, v), axis), glm::dot(prev, v));
      angle *= smoothstep(std::sin(glm::radians(10.0f)), std::sin(glm::radians(30.0f)), across);
      const float step = glm::radians(options_.max_knee_swivel_deg_s) * dt;
      angle = std::clamp(angle, -step, step);
      v = glm::angleAxis(angle, axis) * prev;
    }
  }
  leg.swivel = v;
  leg.swivel_init = true;
  glm::vec3 knee, reached;
  twoBoneIk(hip, leg.upper_len, leg.lower_len, hip + to_target, v, knee, reached);
  const glm::vec3 d1 = (knee - hip) / leg.upper_len;
  const glm::vec3 d2 = glm::normalize(reached - knee);
  // The knee's hinge: across the plane of the hip-ankle line and the swivel.
  const glm::vec3 hinge = glm::normalize(glm::cross(v, axis));
  world_[th] = glm::normalize(frameQuat(d1, hinge) * leg.tracked_frame_c_inv * world_c_[th]);
  world_[sh] = glm::normalize(frameQuat(d2, hinge) * leg.tracked_shin_frame_c_inv * world_c_[sh]);
  world_[ft] = w_foot;
  // The heuristic's state follows, so a foot station that is lost for good hands over
  // without a jump (planted where the foot is now).
  leg.planted = true;
  leg.stepping = false;
  leg.foot_pos = reached;
  leg.foot_yaw = pelvis_yaw_;
}

void PostureSolver::compose(const glm::vec3& hips_position, Posture& out) {
  // Local rotations from the world ones, parents first, with joint limits; undriven joints
  // keep their calibration rotation.
  for (int j = 0; j < n_; ++j) {
    const std::size_t u = static_cast<std::size_t>(j);
    const int parent = skeleton_.parents[u];
    const glm::quat parent_world =
        parent < 0 ? kIdentity : world_[static_cast<std::size_t>(parent)];
    glm::quat local = local_c_[u];
    if (driven_[u]) {
      local = glm::normalize(glm::inverse(parent_world) * world_[u]);
      if (options_.joint_limits && limit_[u] > 0.0f)
        local = limitRotation(local, local_c_[u], limit_[u]);
      if (glm::dot(local, local_c_[u]) < 0.0f) local = -local;
    }
    out.rotations[u] = local;
    world_[u] = glm::normalize(parent_world * local);
  }
  propagate(hips_position);
  out.root_translation = pos_[0];
  // A skeleton whose root is a joint above the hips (a mocap clip's floor origin) with
  // per-joint translations: the root stays where it was at calibration and the hips' own
  // translation carries the body, as in the clip.
  if (hips_ > 0 && skeleton_.parents[static_cast<std::size_t>(hips_)] == 0 && !driven_[0] &&
      out.translations.size() == static_cast<std::size_t>(n_)) {
    out.root_translation = calibration_.posture.root_translation;
    out.translations[static_cast<std::size_t>(hips_)] =
        glm::inverse(world_[0]) * (pos_[static_cast<std::size_t>(hips_)] - pos_c_[0]);
  }
}

void PostureSolver::solve(const SensorFrame& frame, Posture& out) {
  const std::size_t nn = static_cast<std::size_t>(n_);
  if (out.rotations.size() != nn) out.rotations.resize(nn);
  if (out.translations.size() != calibration_.posture.translations.size()) {
    out.translations = calibration_.posture.translations;
  }
  out.time = frame.time;
  const float dt =
      first_ ? 0.0f : static_cast<float>(std::clamp(frame.time - last_time_, 0.0, 0.25));

  // Stations into model space, then their segments' frames.
  std::array<bool, kBodySiteCount> have{};
  std::array<glm::vec3, kBodySiteCount> tp{};
  std::array<glm::quat, kBodySiteCount> tq{};
  for (int s = 0; s < kBodySiteCount; ++s) {
    if (!worn_[static_cast<std::size_t>(s)]) continue;  // a foot station nobody wears
    have[static_cast<std::size_t>(s)] =
        trackStation(s, frame, tp[static_cast<std::size_t>(s)], tq[static_cast<std::size_t>(s)]);
  }
  const std::size_t ci = static_cast<std::size_t>(BodySite::kChest);
  const glm::vec3 chest_tracker = have[ci] ? tp[ci] : calibration_.reference[ci].position;
  std::array<glm::quat, kBodySiteCount> seg_w{};
  std::array<glm::vec3, kBodySiteCount> seg_p{};
  for (int s = 0; s < kBodySiteCount; ++s) {
    const std::size_t u = static_cast<std::size_t>(s);
    if (!have[u]) continue;
    glm::vec3 p;
    glm::quat q;
    calibration_.toModel(static_cast<BodySite>(s), tp[u], tq[u], chest_tracker, p, q);
    seg_w[u] = glm::normalize(q * stations_[u].sensor_to_segment);
    seg_p[u] = p - seg_w[u] * stations_[u].offset;
  }

  // Trunk: pelvis yaw lazily follows the chest; the pelvis takes a share of the bend; the
  // spine joints share the rest evenly.
  const std::size_t C = static_cast<std::size_t>(chest_);
  const std::size_t H = static_cast<std::size_t>(hips_);
  const glm::quat chest_delta =
      have[ci] ? normalizeSafe(seg_w[ci] * glm::inverse(world_c_[C])) : kIdentity;
  glm::vec3 chest_pos = have[ci] ? seg_p[ci] : pos_c_[C];
  glm::quat swing, twist;
  swingTwist(chest_delta, kUp, swing, twist);
  const float yaw_raw = twistAngle(twist, kUp);
  if (first_) {
    chest_yaw_ = pelvis_yaw_ = yaw_raw;
  } else {
    chest_yaw_ += wrapPi(yaw_raw - prev_yaw_raw_);
    pelvis_yaw_ += (chest_yaw_ - pelvis_yaw_) *
                   (1.0f - std::exp(-dt / static_cast<float>(options_.pelvis_follow_s)));
  }
  prev_yaw_raw_ = yaw_raw;
  const float limit = glm::radians(options_.pelvis_twist_limit_deg);
  pelvis_yaw_ = std::clamp(pelvis_yaw_, chest_yaw_ - limit, chest_yaw_ + limit);
  const glm::quat pelvis_yaw = glm::angleAxis(pelvis_yaw_, kUp);
  const glm::quat pelvis =
      glm::normalize(fractionOf(swing, options_.pelvis_tilt_share) * pelvis_yaw);
  const glm::quat spine_rel = normalizeSafe(chest_delta * glm::inverse(pelvis));
  world_[H] = glm::normalize(pelvis * world_c_[H]);
  const float n_trunk = static_cast<float>(trunk_path_.size());
  for (std::size_t i = 0; i < trunk_path_.size(); ++i) {
    const std::size_t j = static_cast<std::size_t>(trunk_path_[i]);
    world_[j] = glm::normalize(fractionOf(spine_rel, static_cast<float>(i + 1) / n_trunk) * pelvis *
                               world_c_[j]);
  }
  glm::vec3 hips_pos = chest_pos;
  for (int j : trunk_path_) {
    const std::size_t u = static_cast<std::size_t>(j);
    hips_pos -= world_[static_cast<std::size_t>(skeleton_.parents[u])] * offset_[u];
  }
  // The trunk's prior: the hips move slowly (a bow turns the trunk about them), so their
  // position is smoothed (constant-velocity Kalman filter, the corner rising with their speed)
  // while the chest's rotation, which carries the bow, is not; the chest follows the hips.
  if (options_.filter && options_.hips_cutoff_hz > 0.0f && have[ci]) {
    if (!hips_init_ || dt <= 0.0f) {
      if (!hips_init_) hips_kf_.init(glm::dvec3(hips_pos), 1.0, 0.0, 0.0);
      hips_init_ = true;
      hips_speed_ = 0.0;
    } else {
      // (At most 8 Hz: a noisy speed would feed back into the corner.)
      const double w =
          6.283185307179586 * std::min(options_.hips_cutoff_hz + options_.hips_beta * hips_speed_,
                                       std::max(8.0, static_cast<double>(options_.hips_cutoff_hz)));
      hips_kf_.predict(dt, dt * w * w * w * w, false);
      hips_kf_.correct(glm::dvec3(hips_pos) - hips_kf_.value(), 1.0);
      hips_speed_ += (glm::length(hips_kf_.velocity()) - hips_speed_) *
                     (1.0 - std::exp(-6.283185307179586 * dt));
    }
    const glm::vec3 smoothed(hips_kf_.value());
    chest_pos += smoothed - hips_pos;
    hips_pos = smoothed;
  }

  // Head and neck.
  const std::size_t hi = static_cast<std::size_t>(BodySite::kHead);
  const glm::quat head_delta =
      have[hi] ? normalizeSafe(seg_w[hi] * glm::inverse(world_c_[static_cast<std::size_t>(head_)]))
               : chest_delta;
  const glm::quat head_rel = normalizeSafe(head_delta * glm::inverse(chest_delta));
  const float n_neck = static_cast<float>(neck_path_.size());
  for (std::size_t i = 0; i < neck_path_.size(); ++i) {
    const std::size_t j = static_cast<std::size_t>(neck_path_[i]);
    world_[j] = glm::normalize(fractionOf(head_rel, static_cast<float>(i + 1) / n_neck) *
                               chest_delta * world_c_[j]);
  }
  // The head sensor also says where the head is: swing the neck joints (not the head,
  // whose rotation the sensor fixes) about the neck's base so the head lands there.
  if (have[hi] && neck_path_.size() > 1) {
    const std::size_t base = static_cast<std::size_t>(neck_path_[0]);
    const glm::vec3 base_pos = chest_pos + world_[C] * offset_[base];
    glm::vec3 head_pos = base_pos;
    for (std::size_t i = 1; i < neck_path_.size(); ++i) {
      const std::size_t j = static_cast<std::size_t>(neck_path_[i]);
      head_pos += world_[static_cast<std::size_t>(skeleton_.parents[j])] * offset_[j];
    }
    const glm::vec3 have_dir = head_pos - base_pos;
    const glm::vec3 want_dir = seg_p[hi] - base_pos;
    if (glm::length(have_dir) > 1e-4f && glm::length(want_dir) > 1e-4f) {
      const glm::quat fix = rotationBetween(glm::normalize(have_dir), glm::normalize(want_dir));
      for (std::size_t i = 0; i + 1 < neck_path_.size(); ++i) {
        const std::size_t j = static_cast<std::size_t>(neck_path_[i]);
        world_[j] = glm::normalize(fix * world_[j]);
      }
    }
  }

  // Provisional arms and legs (carried by the chest and pelvis) for the first pass.
  for (const Arm& arm : arms_) {
    for (int j : {arm.clavicle, arm.upperarm, arm.forearm, arm.hand}) {
      if (j >= 0)
        world_[static_cast<std::size_t>(j)] = chest_delta * world_c_[static_cast<std::size_t>(j)];
    }
    for (const Finger& finger : arm.fingers) {
      for (int j : finger.joint) {
        if (j >= 0)
          world_[static_cast<std::size_t>(j)] = chest_delta * world_c_[static_cast<std::size_t>(j)];
      }
    }
  }
  for (const Leg& leg : legs_) {
    for (int j : {leg.thigh, leg.shin, leg.foot}) {
      if (j >= 0)
        world_[static_cast<std::size_t>(j)] = pelvis * world_c_[static_cast<std::size_t>(j)];
    }
  }
  propagate(hips_pos);

  // Clavicles lift with the upper arm's elevation.
  const glm::vec3 trunk_down = chest_delta * -kUp;
  const glm::vec3 trunk_forward = chest_delta * body_c_.forward;
  std::array<bool, 2> wrist_have{};
  for (int side = 0; side < 2; ++side) {
    Arm& arm = arms_[static_cast<std::size_t>(side)];
    const std::size_t w =
        static_cast<std::size_t>(side == 0 ? BodySite::kLeftWrist : BodySite::kRightWrist);
    wrist_have[static_cast<std::size_t>(side)] = have[w];
    if (arm.clavicle < 0 || !have[w]) continue;
    const glm::vec3 to_elbow = seg_p[w] - pos_[static_cast<std::size_t>(arm.upperarm)];
    if (glm::length(to_elbow) < 1e-5f) continue;
    const float elevation =
        std::acos(std::clamp(glm::dot(glm::normalize(to_elbow), trunk_down), -1.0f, 1.0f));
    const float lift = liftFor(elevation, options_) - arm.lift_c;
    const std::size_t c = static_cast<std::size_t>(arm.clavicle);
    world_[c] = glm::normalize(glm::angleAxis(side == 0 ? lift : -lift, trunk_forward) * world_[c]);
  }
  propagate(hips_pos);

  // Arms, hands, fingers.
  for (int side = 0; side < 2; ++side) {
    const std::size_t w =
        static_cast<std::size_t>(side == 0 ? BodySite::kLeftWrist : BodySite::kRightWrist);
    solveArm(side, frame, wrist_have[static_cast<std::size_t>(side)], seg_w[w], seg_p[w],
             chest_delta);
    if (options_.fingers) {
      const std::size_t ha = static_cast<std::size_t>(arms_[static_cast<std::size_t>(side)].hand);
      solveFingers(side, frame.gloves[static_cast<std::size_t>(side)],
                   normalizeSafe(world_[ha] * glm::inverse(world_c_[ha])));
    }
  }

  // Legs: from the foot sensor when worn and tracked, else the stance's heuristic.
  for (int side = 0; side < 2; ++side) {
    const std::size_t f = static_cast<std::size_t>(footSite(side));
    if (foot_worn_[static_cast<std::size_t>(side)] && have[f]) {
      solveTrackedLeg(side, dt, seg_w[f], seg_p[f]);
    } else {
      solveLeg(side, frame.time, pelvis_yaw, hips_pos);
    }
  }

  compose(hips_pos, out);
  first_ = false;
  last_time_ = frame.time;
}

}  // namespace vistel
