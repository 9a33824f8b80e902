// Where each tracker sensor sits on the body, and how a sensor's reading follows from a
// posture (used by the simulator, and as the nominal mounting for calibration).
//
// A mount is given in the body frame of the calibration posture (BodyFrame: left, up,
// forward; metres), relative to an anchor point: the head joint (head sensor), the chest
// segment's joint (sternum sensor), the hand joint, i.e. the distal end of the forearm
// (wrist sensors), the foot joint, i.e. the ankle (foot sensors, riding on the foot). The head
// sensor rides on the head, the chest sensor on the chest segment and the wrist sensors on the
// forearms, so a wrist sensor's orientation gives the forearm axis (DESIGN.md §5).
#pragma once

#include <array>
#include <span>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/sensors/body_roles.hpp"
#include "common/sensors/sensor_frame.hpp"

namespace vistel {

struct SensorMount {
  BodySite site = BodySite::kHead;
  glm::vec3 offset{0.0f};                      // body frame at calibration, metres
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // sensor axes -> body frame at calibration
};

// Head 11 cm above the head joint, sternum 9 cm forward of the chest joint, wrist sensors
// on the back of the forearm 4 cm above the wrist, foot sensors on the instep 7 cm forward
// of the ankle joint; sensor axes turned a little (as a real strap would) so that
// calibration has something to find.
std::array<SensorMount, kBodySiteCount> defaultSensorMounts();

// The segment a site's sensor rides on, and its anchor joint (see above); -1 when the
// skeleton lacks it (a foot site on a skeleton without feet).
int mountSegment(const JointRoles& roles, BodySite site);
int mountAnchor(const JointRoles& roles, BodySite site);

// A mount fixed in its segment's frame.
struct AttachedSensor {
  int segment = -1;
  glm::vec3 local_offset{0.0f};                      // segment frame, metres
  glm::quat local_rotation{1.0f, 0.0f, 0.0f, 0.0f};  // sensor -> segment frame
};

// Attaches mounts to their segments at the calibration posture, given that posture's
// model-space joint transforms (njoint). A site whose segment the skeleton lacks gets
// segment -1 (sensorPose must not be called on it).
std::array<AttachedSensor, kBodySiteCount> attachSensors(
    const JointRoles& roles, std::span<const glm::mat4> calibration_model,
    std::span<const SensorMount> mounts);

// Model-space pose of an attached sensor for a posture's joint transforms.
void sensorPose(const AttachedSensor& sensor, std::span<const glm::mat4> model, glm::vec3& position,
                glm::quat& orientation);

}  // namespace vistel
