// Small synthetic avatars and clips for session tests (no shared data needed): a
// five-joint body (hips, spine, head, l_arm, r_arm) with a box of skin on each joint,
// and a BVH clip on the same joint names that waves the arms.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "client/net/client_session.hpp"
#include "common/anim/posture.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/avatar/avatar_model.hpp"
#include "tests/net/implicit_avatar.hpp"

namespace vistel::test {

inline AvatarModel makeSyntheticAvatar(const std::string& name = "synthetic", float size = 0.1f) {
  AvatarModel a;
  a.name = name;
  Skeleton& s = a.skeleton;
  s.names = {"hips", "spine", "head", "l_arm", "r_arm"};
  s.parents = {kNoParent, 0, 1, 1, 1};
  s.rest_local.resize(5);
  s.rest_local[0].translation = {0.0f, 1.0f, 0.0f};
  s.rest_local[1].translation = {0.0f, 0.3f, 0.0f};
  s.rest_local[2].translation = {0.0f, 0.3f, 0.0f};
  s.rest_local[3].translation = {0.25f, 0.2f, 0.0f};
  s.rest_local[4].translation = {-0.25f, 0.2f, 0.0f};
  computeInverseBind(s);

  // A box around each joint's rest position, bound to that joint.
  const auto rest = restModelTransforms(s);
  SkinMesh& m = a.skin;
  m.influences = 1;
  for (std::uint16_t j = 0; j < 5; ++j) {
    const glm::vec3 c(rest[j][3]);
    const auto base = static_cast<std::uint32_t>(m.positions.size());
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 d((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f, (k & 4) ? 1.0f : -1.0f);
      m.positions.push_back(c + size * d);
      m.normals.push_back(glm::normalize(d));
      m.joints.push_back(j);
      m.weights.push_back(1.0f);
    }
    const std::uint32_t faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                        {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                        {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (const auto& f : faces) {
      for (std::uint32_t v : f) m.indices.push_back(base + v);
    }
  }
  return a;
}

// The synthetic avatar with an implicit model (tests/net/implicit_avatar.hpp): a
// sphylinder hips->spine, spine->head, spheres on the head and both arm joints, the head
// and arms colliding with each other and with the hips' primitive.
inline AvatarModel makeCollidingAvatar(const std::string& name = "colliding") {
  AvatarModel a = makeSyntheticAvatar(name);
  addImplicitModel(a);
  return a;
}

// A chain of n joints ("j0" .. ), 5 cm apart along +Y, one box of skin on the root:
// for avatars of a given joint count (e.g. 52 like the default humanoid).
inline AvatarModel makeChainAvatar(int joints, const std::string& name = "chain") {
  AvatarModel a = makeSyntheticAvatar(name);
  Skeleton& s = a.skeleton;
  s.names.clear();
  s.parents.clear();
  s.rest_local.assign(static_cast<std::size_t>(joints), Transform{});
  for (int j = 0; j < joints; ++j) {
    s.names.push_back(fmt::format("j{}", j));
    s.parents.push_back(j - 1);
    if (j > 0) s.rest_local[static_cast<std::size_t>(j)].translation = {0.0f, 0.05f, 0.0f};
  }
  computeInverseBind(s);
  for (auto& joint : a.skin.joints) joint = 0;
  return a;
}

// A posture of any skeleton: every joint bent a little, varying with t and the joint.
inline Posture wavingPosture(int joints, double t) {
  Posture p;
  p.time = t;
  p.root_translation = {0.0f, 1.0f, 0.0f};
  for (int j = 0; j < joints; ++j) {
    p.rotations.push_back(glm::angleAxis(0.3f * static_cast<float>(std::sin(t * 4.0 + j)),
                                         glm::normalize(glm::vec3(1.0f, 0.5f, 0.2f * j))));
  }
  return p;
}

// Encoded bytes and hash of an avatar (what a client offers).
struct EncodedAvatar {
  std::vector<std::uint8_t> bytes;
  std::string hash;
};
inline EncodedAvatar encodeSynthetic(const AvatarModel& a) {
  EncodedAvatar e;
  e.bytes = encodeAvatar(a);
  e.hash = avatarContentHash(e.bytes);
  return e;
}

// A posture of the synthetic avatar at time t: arms waving, head nodding.
inline Posture syntheticPosture(double t) {
  Posture p;
  p.time = t;
  p.root_translation = {0.1f * static_cast<float>(std::sin(t)), 1.0f, 0.0f};
  p.rotations.assign(5, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  p.rotations[2] =
      glm::angleAxis(0.3f * static_cast<float>(std::sin(3.0 * t)), glm::vec3(1.0f, 0.0f, 0.0f));
  p.rotations[3] = glm::angleAxis(1.0f + 0.5f * static_cast<float>(std::sin(5.0 * t)),
                                  glm::vec3(0.0f, 0.0f, 1.0f));
  p.rotations[4] = glm::angleAxis(-1.0f - 0.5f * static_cast<float>(std::sin(5.0 * t)),
                                  glm::vec3(0.0f, 0.0f, 1.0f));
  return p;
}

// BVH text of `frames` frames at `fps` on the synthetic avatar's joints (centimetres).
inline std::string syntheticBvh(int frames = 60, double fps = 30.0) {
  std::string s =
      "HIERARCHY\nROOT hips\n{\n  OFFSET 0 100 0\n"
      "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
      "  JOINT spine\n  {\n    OFFSET 0 30 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "    JOINT head\n    {\n      OFFSET 0 30 0\n      CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "      End Site\n      {\n        OFFSET 0 20 0\n      }\n    }\n"
      "    JOINT l_arm\n    {\n      OFFSET 25 20 0\n      CHANNELS 3 Zrotation Xrotation "
      "Yrotation\n"
      "      End Site\n      {\n        OFFSET 50 0 0\n      }\n    }\n"
      "    JOINT r_arm\n    {\n      OFFSET -25 20 0\n      CHANNELS 3 Zrotation Xrotation "
      "Yrotation\n"
      "      End Site\n      {\n        OFFSET -50 0 0\n      }\n    }\n  }\n}\n";
  s += fmt::format("MOTION\nFrames: {}\nFrame Time: {:.8f}\n", frames, 1.0 / fps);
  for (int f = 0; f < frames; ++f) {
    const double a = 40.0 * std::sin(2.0 * 3.14159265358979 * f / frames);
    s += fmt::format("0 100 0 0 0 0  0 0 0  0 {:.3f} 0  {:.3f} 0 0  {:.3f} 0 0\n", a / 4, a, -a);
  }
  return s;
}

}  // namespace vistel::test

namespace vistel::test {

// Session settings for a participant with this avatar.
inline net::SessionSettings sessionFor(const std::string& room, const std::string& name,
                                       const EncodedAvatar& avatar, int joint_count) {
  net::SessionSettings s;
  s.room = room;
  s.name = name;
  s.avatar_bytes = std::make_shared<const std::vector<std::uint8_t>>(avatar.bytes);
  s.avatar_hash = avatar.hash;
  s.avatar_joint_count = joint_count;
  return s;
}

}  // namespace vistel::test
