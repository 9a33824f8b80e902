#include "tests/sensors/humanoid.hpp"

#include <algorithm>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "common/sensors/calibration.hpp"
#include "common/sensors/io/posture_source.hpp"
#include "common/sensors/random.hpp"
#include "common/sensors/rotation_utils.hpp"

namespace vistel::test {

Skeleton makeHumanoid(bool scrambled, std::uint64_t seed) {
  struct J {
    std::string name, parent;
    glm::vec3 offset;  // model-space offset from the parent in the T-pose
  };
  std::vector<J> joints = {{"hips", "", {0.0f, 0.95f, 0.0f}},
                           {"spine", "hips", {0.0f, 0.10f, -0.01f}},
                           {"chest", "spine", {0.0f, 0.12f, 0.0f}},
                           {"upper_chest", "chest", {0.0f, 0.12f, 0.01f}},
                           {"neck", "upper_chest", {0.0f, 0.14f, 0.0f}},
                           {"head", "neck", {0.0f, 0.10f, 0.01f}}};
  for (int side = 0; side < 2; ++side) {
    const float sx = side == 0 ? 1.0f : -1.0f;
    const std::string p = side == 0 ? "l_" : "r_";
    joints.push_back({p + "clavicle", "upper_chest", {sx * 0.03f, 0.08f, 0.0f}});
    joints.push_back({p + "upperarm", p + "clavicle", {sx * 0.15f, 0.0f, -0.01f}});
    joints.push_back({p + "forearm", p + "upperarm", {sx * 0.28f, 0.0f, 0.0f}});
    joints.push_back({p + "hand", p + "forearm", {sx * 0.25f, 0.0f, 0.0f}});
    joints.push_back({p + "thumb1", p + "hand", {sx * 0.02f, -0.01f, 0.03f}});
    joints.push_back({p + "thumb2", p + "thumb1", {sx * 0.03f, 0.0f, 0.02f}});
    joints.push_back({p + "thumb3", p + "thumb2", {sx * 0.03f, 0.0f, 0.0f}});
    const char* fingers[4] = {"index", "middle", "ring", "pinky"};
    const float z[4] = {0.025f, 0.005f, -0.015f, -0.035f};
    for (int f = 0; f < 4; ++f) {
      const std::string base = p + fingers[f];
      joints.push_back({base + "1", p + "hand", {sx * 0.09f, 0.0f, z[f]}});
      joints.push_back({base + "2", base + "1", {sx * 0.04f, 0.0f, 0.0f}});
      joints.push_back({base + "3", base + "2", {sx * 0.025f, 0.0f, 0.0f}});
    }
  }
  for (int side = 0; side < 2; ++side) {
    const float sx = side == 0 ? 1.0f : -1.0f;
    const std::string p = side == 0 ? "l_" : "r_";
    joints.push_back({p + "thigh", "hips", {sx * 0.09f, -0.05f, 0.0f}});
    joints.push_back({p + "shin", p + "thigh", {0.0f, -0.42f, 0.01f}});
    joints.push_back({p + "foot", p + "shin", {0.0f, -0.42f, -0.01f}});
    joints.push_back({p + "toes", p + "foot", {0.0f, -0.06f, 0.13f}});
  }
  Skeleton s;
  std::map<std::string, int> index;
  std::vector<glm::quat> world;
  SimRandom rng(seed);
  for (const J& j : joints) {
    const int parent = j.parent.empty() ? kNoParent : index.at(j.parent);
    index[j.name] = static_cast<int>(s.names.size());
    s.names.push_back(j.name);
    s.parents.push_back(parent);
    glm::quat w(1.0f, 0.0f, 0.0f, 0.0f);
    if (scrambled) {
      w = glm::normalize(
          glm::quat(static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian()),
                    static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian())));
    }
    const glm::quat pw =
        parent < 0 ? glm::quat(1, 0, 0, 0) : world[static_cast<std::size_t>(parent)];
    Transform t;
    t.rotation = glm::normalize(glm::inverse(pw) * w);
    t.translation = glm::inverse(pw) * j.offset;
    s.rest_local.push_back(t);
    world.push_back(w);
  }
  computeInverseBind(s);
  return s;
}

std::vector<glm::vec3> jointPositions(const Skeleton& skeleton, const Posture& posture) {
  std::vector<glm::mat4> model(static_cast<std::size_t>(skeleton.jointCount()));
  poseSkeleton(skeleton, posture, model);
  std::vector<glm::vec3> out(model.size());
  for (std::size_t j = 0; j < model.size(); ++j) out[j] = glm::vec3(model[j][3]);
  return out;
}

void setWorldRotation(const Skeleton& skeleton, Posture& p, int j, const glm::quat& world) {
  std::vector<glm::mat4> model(static_cast<std::size_t>(skeleton.jointCount()));
  poseSkeleton(skeleton, p, model);
  const int parent = skeleton.parents[static_cast<std::size_t>(j)];
  const glm::quat pw =
      parent < 0
          ? glm::quat(1, 0, 0, 0)
          : glm::normalize(glm::quat_cast(glm::mat3(model[static_cast<std::size_t>(parent)])));
  p.rotations[static_cast<std::size_t>(j)] = glm::normalize(glm::inverse(pw) * world);
}

float angleDegrees(const glm::quat& a, const glm::quat& b) {
  return glm::degrees(glm::length(rotationVector(glm::inverse(a) * b)));
}

SensorFrame exactFrame(const Skeleton& skeleton, const Posture& posture,
                       std::span<const AttachedSensor> sensors, double time, bool feet) {
  std::vector<glm::mat4> model(static_cast<std::size_t>(skeleton.jointCount()));
  poseSkeleton(skeleton, posture, model);
  SensorFrame f;
  f.time = time;
  const int count =
      std::min(feet ? kBodySiteCount : kUpperBodySiteCount, static_cast<int>(sensors.size()));
  for (int s = 0; s < count; ++s) {
    if (sensors[static_cast<std::size_t>(s)].segment < 0) continue;
    StationReading& r = f.stations[static_cast<std::size_t>(s)];
    sensorPose(sensors[static_cast<std::size_t>(s)], model, r.position, r.orientation);
    r.time = time;
    r.valid = true;
  }
  return f;
}

Rig makeRig(bool scrambled_frames) {
  Rig rig;
  rig.skeleton = makeHumanoid(scrambled_frames);
  auto roles = resolveJointRoles(rig.skeleton, nullptr);
  EXPECT_TRUE(roles.ok()) << (roles.ok() ? "" : roles.error().message);
  if (roles.ok()) rig.roles = *roles;
  rig.calibration = standardCalibrationPosture(rig.skeleton, rig.roles);
  std::vector<glm::mat4> model(static_cast<std::size_t>(rig.skeleton.jointCount()));
  poseSkeleton(rig.skeleton, rig.calibration, model);
  rig.sensors = attachSensors(rig.roles, model, defaultSensorMounts());
  return rig;
}

void expectReplayMatches(const std::string& recording, const Skeleton& avatar,
                         std::span<const Posture> after_calibration, std::size_t first_calibrated,
                         std::size_t frames) {
  PostureSourceOptions replay_options;
  replay_options.realtime = false;
  auto replay = openPostureSource(recording, avatar, replay_options);
  ASSERT_TRUE(replay.ok()) << replay.error().message;
  std::vector<Posture> replayed;
  std::size_t replay_first_calibrated = 0;
  Posture p;
  PollResult r;
  while ((r = (*replay)->poll(0.1, p)).isFrame()) {
    replayed.push_back(p);
    if ((*replay)->calibrated() && replay_first_calibrated == 0)
      replay_first_calibrated = replayed.size();
  }
  EXPECT_EQ(r.status, PollStatus::kEnd) << r.message;
  ASSERT_EQ(replayed.size(), frames);
  EXPECT_EQ(replay_first_calibrated, first_calibrated);
  ASSERT_GT(first_calibrated, 0u);
  float worst = 0.0f;
  for (std::size_t i = first_calibrated - 1; i < frames; ++i) {
    const auto a = jointPositions(avatar, replayed[i]);
    const auto b = jointPositions(avatar, after_calibration[i - (first_calibrated - 1)]);
    for (std::size_t j = 0; j < a.size(); ++j) worst = std::max(worst, glm::distance(a[j], b[j]));
  }
  EXPECT_LT(worst, 1e-4f);
}

}  // namespace vistel::test
