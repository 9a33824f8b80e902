#include "common/sensors/calibration.hpp"

#include <cmath>
#include <vector>

#include "common/sensors/rotation_utils.hpp"

namespace vistel {
namespace {

float safeRatio(float num, float den) {
  if (!(den > 1e-4f) || !(num > 1e-4f)) return 1.0f;
  const float k = num / den;
  return (k > 0.5f && k < 2.0f) ? k : 1.0f;  // outside this the reading is not a person
}

}  // namespace

void BodyCalibration::toModel(BodySite site, const glm::vec3& position,
                              const glm::quat& orientation, const glm::vec3& chest_position,
                              glm::vec3& out_position, glm::quat& out_orientation) const {
  // Into the skeleton's proportions, about the chest sensor.
  const glm::vec3 chest_scaled(
      chest_position.x, floor_tracker + (chest_position.y - floor_tracker) / proportions.height,
      chest_position.z);
  glm::vec3 p = position;
  switch (site) {
    case BodySite::kChest:
      p = chest_scaled;
      break;
    case BodySite::kHead:
      p = chest_scaled + (position - chest_position) / proportions.torso;
      break;
    case BodySite::kLeftWrist:
      p = chest_scaled + (position - chest_position) / proportions.arm[0];
      break;
    case BodySite::kRightWrist:
      p = chest_scaled + (position - chest_position) / proportions.arm[1];
      break;
    case BodySite::kLeftFoot:
    case BodySite::kRightFoot:
      // Scaled about the chest by the height ratio: vertically the same as the chest's
      // scaling about the floor.
      p = chest_scaled + (position - chest_position) / proportions.height;
      break;
  }
  out_position = align_rotation * p + align_translation;
  out_orientation = align_rotation * orientation;
}

Result<BodyCalibration> calibrateBody(const Skeleton& skeleton, const JointRoles& roles,
                                      const Posture& calibration_posture,
                                      std::span<const SensorFrame> frames,
                                      const CalibrationOptions& options) {
  if (frames.empty()) return fail("calibration: no sensor frames in the calibration window");
  if (calibration_posture.rotations.size() != static_cast<std::size_t>(skeleton.jointCount())) {
    return fail("calibration: the calibration posture has {} rotations for {} joints",
                calibration_posture.rotations.size(), skeleton.jointCount());
  }
  BodyCalibration cal;
  cal.posture = calibration_posture;
  cal.floor_tracker = options.floor_height;

  // Average every station's valid readings (orientations summed in one hemisphere).
  for (int s = 0; s < kBodySiteCount; ++s) {
    glm::dvec3 p_sum(0.0);
    glm::quat q_sum(0.0f, 0.0f, 0.0f, 0.0f);
    glm::quat first(1.0f, 0.0f, 0.0f, 0.0f);
    int n = 0;
    for (const SensorFrame& f : frames) {
      const StationReading& r = f.stations[s];
      if (!r.valid) continue;
      if (n == 0) first = r.orientation;
      p_sum += glm::dvec3(r.position);
      q_sum += glm::dot(first, r.orientation) < 0.0f ? -r.orientation : r.orientation;
      ++n;
    }
    if (n == 0) {
      // A foot station that never reported is not worn (four sensors); the others are needed.
      if (isFootSite(static_cast<BodySite>(s))) continue;
      return fail("calibration: no reading from the {} station in the calibration window",
                  bodySiteName(static_cast<BodySite>(s)));
    }
    StationReading& ref = cal.reference[s];
    ref.position = glm::vec3(p_sum / static_cast<double>(n));
    ref.orientation = normalizeSafe(q_sum);
    ref.valid = true;
    ref.time = frames.back().time;
  }
  for (int h = 0; h < kHandCount; ++h) {
    std::array<double, kGloveSensorCount> sum{};
    int n = 0;
    for (const SensorFrame& f : frames) {
      if (!f.gloves[h].valid) continue;
      for (int i = 0; i < kGloveSensorCount; ++i) sum[i] += f.gloves[h].angles[i];
      ++n;
    }
    if (n == 0) continue;
    for (int i = 0; i < kGloveSensorCount; ++i) {
      cal.glove_zero[h].angles[i] = static_cast<float>(sum[i] / n);
    }
    cal.glove_zero[h].valid = true;
  }

  // The calibration posture's joints, and where the nominal mounts would put the sensors.
  std::vector<glm::mat4> model(static_cast<std::size_t>(skeleton.jointCount()));
  poseSkeleton(skeleton, calibration_posture, model);
  const auto nominal = attachSensors(roles, model, options.nominal_mounts);
  std::array<glm::vec3, kBodySiteCount> predicted{};
  for (int s = 0; s < kBodySiteCount; ++s) {
    if (nominal[s].segment < 0) continue;
    glm::quat unused;
    sensorPose(nominal[s], model, predicted[s], unused);
  }
  const auto& ref = cal.reference;
  const int chest = static_cast<int>(BodySite::kChest);
  const int head = static_cast<int>(BodySite::kHead);

  // Proportions: participant distances over the skeleton's.
  if (options.estimate_proportions) {
    float model_floor = 0.0f;
    bool has_feet = false;
    for (int side = 0; side < 2; ++side) {
      for (Role r : {footRole(side), toesRole(side)}) {
        if (!roles.has(r)) continue;
        const float y = model[static_cast<std::size_t>(roles[r])][3].y;
        model_floor = has_feet ? std::min(model_floor, y) : y;
        has_feet = true;
      }
    }
    BodyProportions& k = cal.proportions;
    k.height = has_feet ? safeRatio(ref[chest].position.y - options.floor_height,
                                    predicted[chest].y - model_floor)
                        : 1.0f;
    k.torso = safeRatio(glm::distance(ref[head].position, ref[chest].position),
                        glm::distance(predicted[head], predicted[chest]));
    for (int side = 0; side < 2; ++side) {
      const int w = static_cast<int>(side == 0 ? BodySite::kLeftWrist : BodySite::kRightWrist);
      k.arm[side] = safeRatio(glm::distance(ref[w].position, ref[chest].position),
                              glm::distance(predicted[w], predicted[chest]));
    }
    if (options.alignment == AlignmentMode::kFacing && has_feet) {
      cal.floor_tracker = options.floor_height;
    }
  }

  // Alignment.
  if (options.alignment == AlignmentMode::kFacing) {
    std::array<glm::vec3, kBodySiteCount> scaled{};
    for (int s = 0; s < kUpperBodySiteCount; ++s) {
      glm::quat unused;
      BodyCalibration identity = cal;
      identity.align_rotation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
      identity.align_translation = glm::vec3(0.0f);
      identity.toModel(static_cast<BodySite>(s), ref[s].position, ref[s].orientation,
                       ref[chest].position, scaled[s], unused);
    }
    const int lw = static_cast<int>(BodySite::kLeftWrist);
    const int rw = static_cast<int>(BodySite::kRightWrist);
    glm::vec3 across_participant = scaled[lw] - scaled[rw];
    glm::vec3 across_model = predicted[lw] - predicted[rw];
    across_participant.y = across_model.y = 0.0f;
    if (glm::length(across_participant) > 1e-3f && glm::length(across_model) > 1e-3f) {
      const float yaw = std::atan2(across_model.z, across_model.x) -
                        std::atan2(across_participant.z, across_participant.x);
      cal.align_rotation = glm::angleAxis(-yaw, glm::vec3(0.0f, 1.0f, 0.0f));
    }
    const glm::vec3 moved = cal.align_rotation * scaled[chest];
    cal.align_translation =
        glm::vec3(predicted[chest].x - moved.x, 0.0f, predicted[chest].z - moved.z);
  }

  // Each sensor's offset to its segment.
  for (int s = 0; s < kBodySiteCount; ++s) {
    const BodySite site = static_cast<BodySite>(s);
    StationCalibration& sc = cal.stations[s];
    sc.segment = mountSegment(roles, site);
    // Not worn (a foot station that never reported) or nothing to ride on (no foot joint).
    if (!ref[s].valid || sc.segment < 0) continue;
    const glm::mat4& m = model[static_cast<std::size_t>(sc.segment)];
    const glm::quat w_seg = worldRotation(m);
    glm::vec3 p_model;
    glm::quat q_model;
    cal.toModel(site, ref[s].position, ref[s].orientation, ref[chest].position, p_model, q_model);
    sc.sensor_to_segment = glm::normalize(glm::inverse(q_model) * w_seg);
    sc.offset = glm::inverse(w_seg) * (p_model - glm::vec3(m[3]));
    sc.calibrated = true;
  }
  return cal;
}

Posture standardCalibrationPosture(const Skeleton& skeleton, const JointRoles& roles) {
  Posture posture = restPosture(skeleton);
  std::vector<glm::mat4> model(static_cast<std::size_t>(skeleton.jointCount()));
  const glm::vec3 down(0.0f, -1.0f, 0.0f);
  // Turn a joint so the direction to its child joint points down (world-space minimal turn).
  auto pointDown = [&](int joint, int child) {
    poseSkeleton(skeleton, posture, model);
    const glm::vec3 dir = glm::vec3(model[child][3]) - glm::vec3(model[joint][3]);
    if (glm::length(dir) < 1e-6f) return;
    const glm::quat turn = rotationBetween(glm::normalize(dir), down);
    const glm::quat world = worldRotation(model[joint]);
    const int parent = skeleton.parents[static_cast<std::size_t>(joint)];
    const glm::quat parent_world = parent >= 0
                                       ? worldRotation(model[static_cast<std::size_t>(parent)])
                                       : glm::quat(1, 0, 0, 0);
    posture.rotations[static_cast<std::size_t>(joint)] =
        glm::normalize(glm::inverse(parent_world) * turn * world);
  };
  for (int side = 0; side < 2; ++side) {
    pointDown(roles[upperarmRole(side)], roles[forearmRole(side)]);
    pointDown(roles[forearmRole(side)], roles[handRole(side)]);
  }
  return posture;
}

}  // namespace vistel
