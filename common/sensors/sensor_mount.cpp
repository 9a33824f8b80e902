#include "common/sensors/sensor_mount.hpp"

#include <vector>

namespace vistel {

std::array<SensorMount, kBodySiteCount> defaultSensorMounts() {
  const glm::vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  std::array<SensorMount, kBodySiteCount> m;
  m[0] = {BodySite::kHead, {0.0f, 0.11f, 0.0f}, glm::angleAxis(glm::radians(12.0f), y)};
  m[1] = {BodySite::kChest, {0.0f, 0.05f, 0.09f}, glm::angleAxis(glm::radians(-8.0f), x)};
  m[2] = {BodySite::kLeftWrist, {0.025f, 0.04f, 0.0f}, glm::angleAxis(glm::radians(20.0f), z)};
  m[3] = {BodySite::kRightWrist, {-0.025f, 0.04f, 0.0f}, glm::angleAxis(glm::radians(-20.0f), z)};
  m[4] = {BodySite::kLeftFoot, {0.0f, 0.0f, 0.07f}, glm::angleAxis(glm::radians(-25.0f), x)};
  m[5] = {BodySite::kRightFoot, {0.0f, 0.0f, 0.07f}, glm::angleAxis(glm::radians(-25.0f), x)};
  return m;
}

int mountSegment(const JointRoles& roles, BodySite site) {
  switch (site) {
    case BodySite::kHead:
      return roles[Role::kHead];
    case BodySite::kChest:
      return roles.chestSegment();
    case BodySite::kLeftWrist:
      return roles[Role::kLForearm];
    case BodySite::kRightWrist:
      return roles[Role::kRForearm];
    case BodySite::kLeftFoot:
      return roles[footRole(0)];
    case BodySite::kRightFoot:
      return roles[footRole(1)];
  }
  return -1;
}

int mountAnchor(const JointRoles& roles, BodySite site) {
  switch (site) {
    case BodySite::kLeftWrist:
      return roles[Role::kLHand];
    case BodySite::kRightWrist:
      return roles[Role::kRHand];
    default:
      return mountSegment(roles, site);
  }
}

std::array<AttachedSensor, kBodySiteCount> attachSensors(const JointRoles& roles,
                                                         std::span<const glm::mat4> model,
                                                         std::span<const SensorMount> mounts) {
  std::vector<glm::vec3> positions(model.size());
  for (std::size_t j = 0; j < model.size(); ++j) positions[j] = glm::vec3(model[j][3]);
  const BodyFrame body = bodyFrameAt(roles, positions);
  const glm::quat body_rot = glm::quat_cast(body.matrix());
  std::array<AttachedSensor, kBodySiteCount> out;
  for (const SensorMount& mount : mounts) {
    const int s = static_cast<int>(mount.site);
    const int seg = mountSegment(roles, mount.site);
    const int anchor = mountAnchor(roles, mount.site);
    if (seg < 0 || anchor < 0 || static_cast<std::size_t>(seg) >= model.size() ||
        static_cast<std::size_t>(anchor) >= model.size()) {
      out[s] = AttachedSensor{};  // the skeleton has no such segment (e.g. no feet)
      continue;
    }
    const glm::quat seg_rot = glm::normalize(glm::quat_cast(glm::mat3(model[seg])));
    const glm::vec3 p_world = positions[anchor] + body.matrix() * mount.offset;
    out[s].segment = seg;
    out[s].local_offset = glm::inverse(seg_rot) * (p_world - positions[seg]);
    out[s].local_rotation = glm::normalize(glm::inverse(seg_rot) * body_rot * mount.rotation);
  }
  return out;
}

void sensorPose(const AttachedSensor& sensor, std::span<const glm::mat4> model, glm::vec3& position,
                glm::quat& orientation) {
  const glm::mat4& m = model[static_cast<std::size_t>(sensor.segment)];
  const glm::quat seg_rot = glm::normalize(glm::quat_cast(glm::mat3(m)));
  position = glm::vec3(m[3]) + seg_rot * sensor.local_offset;
  orientation = glm::normalize(seg_rot * sensor.local_rotation);
}

}  // namespace vistel
