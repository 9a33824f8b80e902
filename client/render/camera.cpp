#include "client/render/camera.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace vistel {

Sphere sphereAroundBox(const glm::vec3& box_min, const glm::vec3& box_max) {
  return Sphere{(box_min + box_max) * 0.5f, glm::length(box_max - box_min) * 0.5f};
}

CameraPose frameSphere(const Sphere& sphere, const glm::vec3& direction, float vertical_fov,
                       float aspect, float fill, Lens& lens, float extra_far) {
  // The narrower half-angle decides the distance at which the sphere fits.
  const float half_v = vertical_fov * 0.5f;
  const float half_h = std::atan(std::tan(half_v) * aspect);
  const float half = std::min(half_v, half_h) * std::clamp(fill, 0.05f, 1.0f);
  const float radius = std::max(sphere.radius, 0.05f);
  const float distance = radius / std::sin(half);
  const glm::vec3 forward = glm::normalize(direction);
  CameraPose pose = makePose(sphere.center - forward * distance, forward, glm::vec3(0, 1, 0));
  // Near and far planes bracket the sphere (and the floor beyond it).
  lens.vertical_fov = vertical_fov;
  lens.near_plane = std::max(0.05f, (distance - radius) * 0.5f);
  lens.far_plane = distance + radius + extra_far;
  return pose;
}

glm::vec3 orbitDirection(float yaw, float pitch) {
  pitch = std::clamp(pitch, -1.45f, 1.45f);
  // yaw = 0, pitch = 0 looks along -Z; positive pitch looks down.
  return glm::vec3(-std::sin(yaw) * std::cos(pitch), -std::sin(pitch),
                   -std::cos(yaw) * std::cos(pitch));
}

CameraPose makePose(const glm::vec3& position, const glm::vec3& forward, const glm::vec3& up) {
  CameraPose pose;
  pose.position = position;
  const float fl = glm::length(forward);
  pose.forward = fl > 1e-6f ? forward / fl : glm::vec3(0, 0, -1);
  // Remove the forward part of up; pick another up when they are parallel.
  glm::vec3 u = up - pose.forward * glm::dot(up, pose.forward);
  if (glm::length(u) < 1e-4f) {
    const glm::vec3 alt =
        std::abs(pose.forward.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(0, 0, -1);
    u = alt - pose.forward * glm::dot(alt, pose.forward);
  }
  pose.up = glm::normalize(u);
  return pose;
}

EyeCamera makeEye(const CameraPose& pose, const Lens& lens, float eye_offset, float focal_distance,
                  const glm::ivec4& viewport) {
  EyeCamera eye;
  const glm::vec3 right = glm::normalize(glm::cross(pose.forward, pose.up));
  eye.position = pose.position + right * eye_offset;
  eye.view = glm::lookAt(eye.position, eye.position + pose.forward, pose.up);
  eye.viewport = viewport;
  // Off-axis frustum: shift the window so that the plane at focal_distance is shared.
  const float aspect =
      viewport.w > 0 ? static_cast<float>(viewport.z) / static_cast<float>(viewport.w) : 1.0f;
  const float top = lens.near_plane * std::tan(lens.vertical_fov * 0.5f);
  const float half_w = top * aspect;
  const float shift = focal_distance > 0.0f ? eye_offset * lens.near_plane / focal_distance : 0.0f;
  eye.projection =
      glm::frustum(-half_w - shift, half_w - shift, -top, top, lens.near_plane, lens.far_plane);
  return eye;
}

bool projectToPixel(const EyeCamera& eye, const glm::vec3& p_room, glm::vec3& out_pixel) {
  const glm::vec4 c = eye.projection * eye.view * glm::vec4(p_room, 1.0f);
  if (c.w <= 1e-6f) return false;
  const glm::vec3 ndc = glm::vec3(c) / c.w;
  out_pixel.x = static_cast<float>(eye.viewport.x) +
                (ndc.x * 0.5f + 0.5f) * static_cast<float>(eye.viewport.z);
  out_pixel.y = static_cast<float>(eye.viewport.y) +
                (ndc.y * 0.5f + 0.5f) * static_cast<float>(eye.viewport.w);
  out_pixel.z = ndc.z;
  return true;
}

}  // namespace vistel
