// Calibration (DESIGN.md §5): while the participant holds the calibration posture, fix each
// sensor's offset to its body segment, the map from tracker space into model space, and —
// optionally — the participant's proportions relative to the solver's skeleton.
//
// Model: a sensor is rigid on its segment, so with W the segment's world rotation and p its
// position, W(t) = A * Q(t) * X and q_A(t) = p(t) + W(t) * offset, where Q, q are the
// sensor's reading, A the tracker-to-model map, and X, offset what calibration finds (from
// the calibration posture's W, p and the averaged readings). Proportions: the participant's
// chest-to-wrist, chest-to-head and floor-to-chest distances against the same distances of
// the skeleton with the nominal mounts; the solver maps readings into the skeleton's
// proportions before using them (BodyCalibration::toModel).
#pragma once

#include <array>
#include <span>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/sensors/body_roles.hpp"
#include "common/sensors/sensor_frame.hpp"
#include "common/sensors/sensor_mount.hpp"

namespace vistel {

enum class AlignmentMode : std::uint8_t {
  kFixed,   // tracker space is model space (the driver's transmitter transform maps it)
  kFacing,  // turn about +Y and shift so the participant stands where the calibration
            // posture stands, facing the same way, feet on the floor
};

struct CalibrationOptions {
  AlignmentMode alignment = AlignmentMode::kFixed;
  bool estimate_proportions = false;  // off when the skeleton is the participant's own body
  float floor_height = 0.0f;          // tracker-space height of the floor, metres
  double window_s = 0.25;             // how long callers average the calibration pose
  std::array<SensorMount, kBodySiteCount> nominal_mounts = defaultSensorMounts();
};

struct StationCalibration {
  bool calibrated = false;
  int segment = -1;                                     // joint the sensor rides on
  glm::quat sensor_to_segment{1.0f, 0.0f, 0.0f, 0.0f};  // X above
  glm::vec3 offset{0.0f};  // sensor position in the segment frame, metres (model proportions)
};

// Participant size over skeleton size (1 = same).
struct BodyProportions {
  float height = 1.0f;                   // floor to chest sensor
  float torso = 1.0f;                    // chest sensor to head sensor
  std::array<float, 2> arm{1.0f, 1.0f};  // chest sensor to wrist sensor, left / right
};

struct BodyCalibration {
  Posture posture;  // the calibration posture on the solver's skeleton
  glm::quat align_rotation{1.0f, 0.0f, 0.0f, 0.0f};  // A: tracker -> model (about +Y)
  glm::vec3 align_translation{0.0f};
  std::array<StationCalibration, kBodySiteCount> stations{};
  BodyProportions proportions;
  float floor_tracker = 0.0f;  // tracker-space floor height (for proportions)
  std::array<StationReading, kBodySiteCount> reference{};  // the averaged readings
  std::array<GloveReading, kHandCount> glove_zero{};       // averaged glove readings

  // A reading's pose in model space with the skeleton's proportions. `chest` is the current
  // chest reading (the proportions scale about it); allocation-free.
  void toModel(BodySite site, const glm::vec3& position, const glm::quat& orientation,
               const glm::vec3& chest_position, glm::vec3& out_position,
               glm::quat& out_orientation) const;
};

// Averages the valid readings of `frames` (stations and gloves) and calibrates against the
// calibration posture. Fails, naming the station, when one of the four upper-body stations
// never reported in the window (the solver cannot place that segment), or when no frame is
// given. A foot station that never reported is not worn: its StationCalibration stays
// uncalibrated (as does one whose skeleton has no foot joint) and the solver infers that
// leg.
Result<BodyCalibration> calibrateBody(const Skeleton& skeleton, const JointRoles& roles,
                                      const Posture& calibration_posture,
                                      std::span<const SensorFrame> frames,
                                      const CalibrationOptions& options);

// The standard calibration posture for a live participant on an avatar: the skeleton's rest
// posture with both arms hanging straight down (the minimal turn of each upper arm and
// forearm, which takes a T- or A-pose to palms facing the thighs).
Posture standardCalibrationPosture(const Skeleton& skeleton, const JointRoles& roles);

}  // namespace vistel
