// A canonical 52-joint humanoid for the sensor tests (T-pose rest, metres, +Y up, facing
// +Z, left = +X), optionally with scrambled joint frames (random rest rotations with the
// same joint positions), as mocap skeletons have.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/sensors/body_roles.hpp"
#include "common/sensors/sensor_frame.hpp"
#include "common/sensors/sensor_mount.hpp"

namespace vistel::test {

Skeleton makeHumanoid(bool scrambled_frames = false, std::uint64_t seed = 7);

// Model-space joint positions of a posture.
std::vector<glm::vec3> jointPositions(const Skeleton& skeleton, const Posture& posture);

// Sets joint j's world rotation (model space) to `world` in posture p (children keep their
// local rotations).
void setWorldRotation(const Skeleton& skeleton, Posture& p, int j, const glm::quat& world);

// Angle between two rotations in degrees, precise near zero (acos is not).
float angleDegrees(const glm::quat& a, const glm::quat& b);

// A noiseless sensor frame for a posture: every station at its attached sensor's pose (the
// four upper-body ones; the feet too when `feet`).
SensorFrame exactFrame(const Skeleton& skeleton, const Posture& posture,
                       std::span<const AttachedSensor> sensors, double time, bool feet = false);

// The humanoid in the standard calibration posture with the default sensor mounts attached:
// what a posture-solver test solves from.
struct Rig {
  Skeleton skeleton;
  JointRoles roles{};
  Posture calibration;
  std::array<AttachedSensor, kBodySiteCount> sensors{};
};
Rig makeRig(bool scrambled_frames);

// Replays a .vrec (not in real time) on `avatar` and expects what a live session solved:
// calibration at the same frame (first_calibrated, 1-based), then the same postures
// (`after_calibration`, from that frame on) within 0.1 mm at every joint, `frames` in all.
void expectReplayMatches(const std::string& recording, const Skeleton& avatar,
                         std::span<const Posture> after_calibration, std::size_t first_calibrated,
                         std::size_t frames);

}  // namespace vistel::test
