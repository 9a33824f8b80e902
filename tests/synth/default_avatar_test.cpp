// The default avatar (offline/synth/default_avatar.hpp): counts, topology, shape,
// skeleton, A-pose, separate fingers, skin weights, determinism, posing. The avatar is
// built once per test binary run (ctest runs each test in its own process: ~1 s each).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "offline/synth/default_avatar.hpp"
#include "tests/support/test_support.hpp"
#include "tests/synth/mesh_checks.hpp"

namespace vistel {
namespace {

// RULES.md / joint_map.hpp: the canonical humanoid joints, in hierarchy order.
const std::vector<std::string>& canonicalNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out = {"hips", "spine", "chest", "upper_chest", "neck", "head"};
    for (const std::string side : {"l_", "r_"}) {
      for (const char* j : {"clavicle", "upperarm", "forearm", "hand"}) out.push_back(side + j);
      for (const char* f : {"thumb", "index", "middle", "ring", "pinky"}) {
        for (int k = 1; k <= 3; ++k) out.push_back(side + f + std::to_string(k));
      }
    }
    for (const std::string side : {"l_", "r_"}) {
      for (const char* j : {"thigh", "shin", "foot", "toes"}) out.push_back(side + j);
    }
    return out;
  }();
  return names;
}

const Result<AvatarModel>& defaultAvatar() {
  static const Result<AvatarModel> avatar = makeDefaultAvatar();
  return avatar;
}

class DefaultAvatar : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(defaultAvatar().ok()) << defaultAvatar().error().message; }
  const AvatarModel& avatar() const { return defaultAvatar().value(); }
  const SkinMesh& skin() const { return avatar().skin; }
  int joint(const std::string& name) const { return avatar().skeleton.find(name); }
  glm::vec3 jointPosition(const std::string& name) const {
    const std::vector<glm::mat4> model = restModelTransforms(avatar().skeleton);
    return glm::vec3(model[static_cast<std::size_t>(joint(name))][3]);
  }
  // The joint with the largest weight on vertex v.
  int dominantJoint(std::size_t v) const {
    const auto k = static_cast<std::size_t>(skin().influences);
    std::size_t best = 0;
    for (std::size_t s = 1; s < k; ++s) {
      if (skin().weights[v * k + s] > skin().weights[v * k + best]) best = s;
    }
    return skin().joints[v * k + best];
  }
};

TEST_F(DefaultAvatar, IsValidWithCountsInRange) {
  EXPECT_EQ(avatar().name, "vistel-default");
  const Status s = validateAvatar(avatar());
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_EQ(skin().vertexCount(), 10000);
  EXPECT_GE(skin().vertexCount(), 5000);
  EXPECT_LE(skin().vertexCount(), 15000);
  EXPECT_EQ(skin().influences, 4);
  EXPECT_LE(maxInfluencesUsed(skin()), 4);
}

TEST_F(DefaultAvatar, SkinIsAClosedOrientedManifoldInOnePiece) {
  const test::Topology topo = test::analyseTopology(skin().positions, skin().indices);
  EXPECT_TRUE(topo.edges_paired) << "an edge is not shared by exactly two opposite triangles";
  EXPECT_EQ(topo.nonmanifold_vertices, 0);
  EXPECT_EQ(topo.degenerate_triangles, 0);
  EXPECT_EQ(topo.unused_vertices, 0);
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler, 2) << "the skin should be a topological sphere (genus 0)";
}

TEST_F(DefaultAvatar, SkinDoesNotIntersectItself) {
  EXPECT_EQ(test::countSelfIntersections(skin().positions, skin().indices), 0);
}

TEST_F(DefaultAvatar, TrianglesAreWellShaped) {
  // Smallest angle per triangle: none near zero, few below 15 degrees.
  int below15 = 0;
  float smallest = 180.0f;
  for (std::size_t t = 0; t < skin().indices.size(); t += 3) {
    const std::array<glm::vec3, 3> p{skin().positions[skin().indices[t]],
                                     skin().positions[skin().indices[t + 1]],
                                     skin().positions[skin().indices[t + 2]]};
    for (std::size_t k = 0; k < 3; ++k) {
      const glm::vec3 a = glm::normalize(p[(k + 1) % 3] - p[k]);
      const glm::vec3 b = glm::normalize(p[(k + 2) % 3] - p[k]);
      const float angle = glm::degrees(std::acos(std::clamp(glm::dot(a, b), -1.0f, 1.0f)));
      smallest = std::min(smallest, angle);
      if (angle < 15.0f) ++below15;
    }
  }
  EXPECT_GT(smallest, 2.0f);
  EXPECT_LT(below15, skin().triangleCount() / 50) << "more than 2% of triangles are slivers";
}

TEST_F(DefaultAvatar, HumanSizedStandingOnTheGround) {
  const double volume = enclosedVolume(skin().positions, skin().indices);
  EXPECT_GT(volume, 0.06);
  EXPECT_LT(volume, 0.09);
  const Bounds b = computeBounds(skin().positions);
  EXPECT_NEAR(b.min.y, 0.0f, 1e-6f);
  EXPECT_NEAR(b.max.y, 1.75f, 0.01f);
  // Symmetric about x = 0 (left = +x), deeper in front (nose, toes) than behind.
  EXPECT_NEAR(b.min.x, -b.max.x, 0.01f);
  EXPECT_GT(b.max.z, -b.min.z);
  // Facing +Z: toes reach further forward than heels back; the frontmost point of the
  // head is the nose, on the mid-plane.
  float toes = -1.0f, heels = 1.0f;
  glm::vec3 nose(0.0f, 0.0f, -1.0f);
  for (const glm::vec3& p : skin().positions) {
    if (p.y < 0.03f) {
      toes = std::max(toes, p.z);
      heels = std::min(heels, p.z);
    }
    if (p.y > 1.55f && p.z > nose.z) nose = p;
  }
  EXPECT_GT(toes, -heels + 0.05f);
  EXPECT_LT(std::abs(nose.x), 0.01f);
  EXPECT_GT(nose.z, 0.09f);
}

TEST_F(DefaultAvatar, SkeletonHasTheCanonicalJointsParentsFirst) {
  const Skeleton& s = avatar().skeleton;
  ASSERT_EQ(s.names, canonicalNames());
  EXPECT_EQ(s.parents[0], kNoParent);
  for (int j = 1; j < s.jointCount(); ++j) EXPECT_LT(s.parents[static_cast<std::size_t>(j)], j);
  const auto parent = [&](const std::string& name) {
    return s.names[static_cast<std::size_t>(s.parents[static_cast<std::size_t>(s.find(name))])];
  };
  EXPECT_EQ(parent("spine"), "hips");
  EXPECT_EQ(parent("neck"), "upper_chest");
  EXPECT_EQ(parent("head"), "neck");
  for (const std::string side : {"l_", "r_"}) {
    EXPECT_EQ(parent(side + "clavicle"), "upper_chest");
    EXPECT_EQ(parent(side + "upperarm"), side + "clavicle");
    EXPECT_EQ(parent(side + "forearm"), side + "upperarm");
    EXPECT_EQ(parent(side + "hand"), side + "forearm");
    for (const char* f : {"thumb", "index", "middle", "ring", "pinky"}) {
      EXPECT_EQ(parent(side + f + "1"), side + "hand");
      EXPECT_EQ(parent(side + f + "2"), side + f + "1");
      EXPECT_EQ(parent(side + f + "3"), side + f + "2");
    }
    EXPECT_EQ(parent(side + "thigh"), "hips");
    EXPECT_EQ(parent(side + "shin"), side + "thigh");
    EXPECT_EQ(parent(side + "foot"), side + "shin");
    EXPECT_EQ(parent(side + "toes"), side + "foot");
  }
  // Rest rotations are identity; inverse bind matrices match the rest posture.
  const std::vector<glm::mat4> model = restModelTransforms(s);
  for (std::size_t j = 0; j < model.size(); ++j) {
    EXPECT_EQ(s.rest_local[j].rotation, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    const glm::mat4 identity = model[j] * s.inverse_bind[j];
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) EXPECT_NEAR(identity[c][r], c == r ? 1.0f : 0.0f, 1e-6f);
    }
  }
}

TEST_F(DefaultAvatar, RestsInAnAPoseFacingForward) {
  for (const std::string side : {"l_", "r_"}) {
    const glm::vec3 shoulder = jointPosition(side + "upperarm");
    const glm::vec3 elbow = jointPosition(side + "forearm");
    const glm::vec3 d = glm::normalize(elbow - shoulder);
    const float below = glm::degrees(std::asin(-d.y));
    EXPECT_GE(below, 40.0f) << side;
    EXPECT_LE(below, 45.0f) << side;
    EXPECT_GT(side == "l_" ? d.x : -d.x, 0.7f) << "arms reach out sideways";
    // Fingers fan out: index and pinky diverge.
    const glm::vec3 index =
        glm::normalize(jointPosition(side + "index3") - jointPosition(side + "index1"));
    const glm::vec3 pinky =
        glm::normalize(jointPosition(side + "pinky3") - jointPosition(side + "pinky1"));
    EXPECT_GT(glm::degrees(std::acos(glm::dot(index, pinky))), 10.0f) << side;
  }
  EXPECT_GT(jointPosition("l_hand").x, 0.4f);
  EXPECT_LT(jointPosition("r_hand").x, -0.4f);
  // Feet point forward: the toes are in front of the ankles.
  EXPECT_GT(jointPosition("l_toes").z, jointPosition("l_foot").z + 0.08f);
}

TEST_F(DefaultAvatar, FingersAreSeparate) {
  // Fingertip joints lie inside the skin; the points half-way between neighbouring
  // fingers' last two joints lie outside it.
  const std::array<const char*, 5> fingers{"thumb", "index", "middle", "ring", "pinky"};
  for (const std::string side : {"l_", "r_"}) {
    for (const char* f : fingers) {
      for (const char* k : {"2", "3"}) {
        const glm::vec3 p = jointPosition(side + f + k);
        EXPECT_GT(test::windingNumber(skin().positions, skin().indices, p), 0.5) << side << f << k;
      }
    }
    for (std::size_t i = 1; i + 1 < fingers.size(); ++i) {
      for (const char* k : {"2", "3"}) {
        const glm::vec3 a = jointPosition(side + fingers[i] + k);
        const glm::vec3 b = jointPosition(side + fingers[i + 1] + k);
        EXPECT_LT(test::windingNumber(skin().positions, skin().indices, 0.5f * (a + b)), 0.5)
            << side << fingers[i] << "/" << fingers[i + 1] << " joint " << k;
      }
    }
  }
}

TEST_F(DefaultAvatar, WeightsAreNormalisedAndLocal) {
  const Skeleton& s = avatar().skeleton;
  const auto k = static_cast<std::size_t>(skin().influences);
  // Which finger (or leg) a joint belongs to: "l_index", "r_thigh" -> "r_leg", else "".
  const auto finger = [&](int j) -> std::string {
    const std::string& n = s.names[static_cast<std::size_t>(j)];
    for (const char* f : {"thumb", "index", "middle", "ring", "pinky"}) {
      if (n.find(f) != std::string::npos) return n.substr(0, 2) + f;
    }
    return "";
  };
  const auto leg = [&](int j) -> std::string {
    const std::string& n = s.names[static_cast<std::size_t>(j)];
    for (const char* part : {"thigh", "shin", "foot", "toes"}) {
      if (n.find(part) != std::string::npos) return n.substr(0, 2) + "leg";
    }
    return "";
  };
  int finger_vertices = 0, thigh_vertices = 0;
  for (std::size_t v = 0; v < skin().positions.size(); ++v) {
    float sum = 0.0f;
    for (std::size_t i = 0; i < k; ++i) sum += skin().weights[v * k + i];
    ASSERT_NEAR(sum, 1.0f, 1e-5f) << "vertex " << v;
    const int own = dominantJoint(v);
    const std::string own_finger = finger(own), own_leg = leg(own);
    finger_vertices += own_finger.empty() ? 0 : 1;
    thigh_vertices += own_leg.empty() ? 0 : 1;
    for (std::size_t i = 0; i < k; ++i) {
      if (skin().weights[v * k + i] <= 0.0f) continue;
      const int j = skin().joints[v * k + i];
      // A finger vertex depends only on its own finger and the hand.
      if (!own_finger.empty() && !finger(j).empty()) {
        ASSERT_EQ(finger(j), own_finger)
            << "vertex " << v << " of " << s.names[static_cast<std::size_t>(own)];
      }
      // A leg vertex never depends on the other leg.
      if (!own_leg.empty() && !leg(j).empty()) {
        ASSERT_EQ(leg(j), own_leg)
            << "vertex " << v << " of " << s.names[static_cast<std::size_t>(own)];
      }
    }
  }
  EXPECT_GT(finger_vertices, 500);
  EXPECT_GT(thigh_vertices, 500);
}

TEST_F(DefaultAvatar, WeightsBlendSmoothlyAcrossTheElbow) {
  // Along the arm, the forearm's weight rises from 0 to 1 over a band around the elbow
  // (a few centimetres), not in a step.
  const glm::vec3 shoulder = jointPosition("l_upperarm");
  const glm::vec3 elbow = jointPosition("l_forearm");
  const glm::vec3 wrist = jointPosition("l_hand");
  const int forearm = joint("l_forearm");
  const auto k = static_cast<std::size_t>(skin().influences);
  int partial = 0;
  for (std::size_t v = 0; v < skin().positions.size(); ++v) {
    const glm::vec3 p = skin().positions[v];
    const float t_upper = glm::dot(p - shoulder, glm::normalize(elbow - shoulder));
    if (p.x < 0.2f || glm::distance(p, elbow) > 0.12f) continue;
    float w = 0.0f;
    for (std::size_t i = 0; i < k; ++i) {
      if (skin().joints[v * k + i] == forearm) w += skin().weights[v * k + i];
    }
    // Far up the upper arm: no forearm weight; far down the forearm: all of it.
    const float along_fore = glm::dot(p - elbow, glm::normalize(wrist - elbow));
    if (t_upper < glm::distance(shoulder, elbow) - 0.08f) {
      EXPECT_LT(w, 0.05f) << v;
    }
    if (along_fore > 0.08f) {
      EXPECT_GT(w, 0.95f) << v;
    }
    if (w > 0.2f && w < 0.8f) ++partial;
  }
  EXPECT_GT(partial, 20) << "the elbow should have a band of blended weights";
}

TEST_F(DefaultAvatar, WeightsChangeGraduallyAcrossEdges) {
  // No joint's weight changes by more than ~0.4 between neighbouring vertices (no seams
  // when the skeleton moves), and across 99% of edges by less than 0.3.
  const auto k = static_cast<std::size_t>(skin().influences);
  const auto weightOf = [&](std::size_t v, int j) {
    float w = 0.0f;
    for (std::size_t s = 0; s < k; ++s) {
      if (skin().joints[v * k + s] == j) w += skin().weights[v * k + s];
    }
    return w;
  };
  std::vector<float> jumps;
  for (std::size_t t = 0; t < skin().indices.size(); t += 3) {
    for (std::size_t e = 0; e < 3; ++e) {
      const std::size_t a = skin().indices[t + e], b = skin().indices[t + (e + 1) % 3];
      float jump = 0.0f;
      for (std::size_t s = 0; s < k; ++s) {
        for (const std::size_t v : {a, b}) {
          const int j = skin().joints[v * k + s];
          jump = std::max(jump, std::abs(weightOf(a, j) - weightOf(b, j)));
        }
      }
      jumps.push_back(jump);
    }
  }
  std::sort(jumps.begin(), jumps.end());
  EXPECT_LT(jumps.back(), 0.45f);
  EXPECT_LT(jumps[jumps.size() * 99 / 100], 0.3f);
}

TEST_F(DefaultAvatar, RestPostureReproducesTheMesh) {
  const Skeleton& s = avatar().skeleton;
  const auto n = static_cast<std::size_t>(s.jointCount());
  std::vector<glm::mat4> model(n), skinning(n);
  poseSkeleton(s, restPosture(s), model);
  skinningMatrices(s, model, skinning);
  std::vector<glm::vec3> positions(skin().positions.size()), normals(skin().positions.size());
  skinLinear(skin(), skinning, 0, positions, normals);
  for (std::size_t v = 0; v < positions.size(); ++v) {
    ASSERT_LT(glm::distance(positions[v], skin().positions[v]), 1e-6f) << "vertex " << v;
  }
}

TEST_F(DefaultAvatar, ElbowBentNinetyDegreesKeepsItsShape) {
  const Skeleton& s = avatar().skeleton;
  const auto n = static_cast<std::size_t>(s.jointCount());
  // Flex the left elbow by 90 degrees, swinging the forearm forward.
  const glm::vec3 shoulder = jointPosition("l_upperarm");
  const glm::vec3 elbow = jointPosition("l_forearm");
  const glm::vec3 upper = glm::normalize(elbow - shoulder);
  const glm::vec3 axis = glm::normalize(glm::cross(upper, glm::vec3(0.0f, 0.0f, 1.0f)));
  Posture posture = restPosture(s);
  posture.rotations[static_cast<std::size_t>(joint("l_forearm"))] =
      glm::angleAxis(std::numbers::pi_v<float> / 2.0f, axis);
  std::vector<glm::mat4> model(n), skinning(n);
  poseSkeleton(s, posture, model);
  skinningMatrices(s, model, skinning);
  std::vector<glm::vec3> positions(skin().positions.size()), normals(skin().positions.size());
  skinLinear(skin(), skinning, 0, positions, normals);
  // The forearm now points forward.
  const glm::vec3 wrist(model[static_cast<std::size_t>(joint("l_hand"))][3]);
  EXPECT_GT(glm::dot(glm::normalize(wrist - elbow), glm::vec3(0.0f, 0.0f, 1.0f)), 0.9f);
  // Volume is kept within 1% of the body and skin near the elbow stays away from the bone.
  const double rest = enclosedVolume(skin().positions, skin().indices);
  const double bent = enclosedVolume(positions, skin().indices);
  EXPECT_NEAR(bent / rest, 1.0, 0.01);
  const auto distanceToBones = [&](const glm::vec3& p, const glm::vec3& a, const glm::vec3& b,
                                   const glm::vec3& c) {
    const auto seg = [](const glm::vec3& q, const glm::vec3& s0, const glm::vec3& s1) {
      const float t =
          std::clamp(glm::dot(q - s0, s1 - s0) / glm::dot(s1 - s0, s1 - s0), 0.0f, 1.0f);
      return glm::distance(q, s0 + t * (s1 - s0));
    };
    return std::min(seg(p, a, b), seg(p, b, c));
  };
  float worst = 1.0f;
  for (std::size_t v = 0; v < positions.size(); ++v) {
    if (glm::distance(skin().positions[v], elbow) > 0.1f) continue;
    const float before =
        distanceToBones(skin().positions[v], shoulder, elbow, jointPosition("l_hand"));
    const float after = distanceToBones(positions[v], shoulder, elbow, wrist);
    worst = std::min(worst, after / before);
  }
  EXPECT_GT(worst, 0.3f) << "skin at the inner elbow collapses onto the bones";
}

TEST_F(DefaultAvatar, WritesAQuickLookObj) {
  const std::string path = test::scratchDir() + "/default_avatar.obj";
  ASSERT_TRUE(test::writeObj(path, skin().positions, skin().indices));
  std::ifstream in(path);
  std::string line;
  int vertices = 0, faces = 0;
  while (std::getline(in, line)) {
    vertices += line.rfind("v ", 0) == 0 ? 1 : 0;
    faces += line.rfind("f ", 0) == 0 ? 1 : 0;
  }
  EXPECT_EQ(vertices, skin().vertexCount());
  EXPECT_EQ(faces, skin().triangleCount());
}

TEST_F(DefaultAvatar, IsDeterministic) {
  // A second build gives the same bytes (single-threaded; no unordered iteration).
  const Result<AvatarModel> again = makeDefaultAvatar();
  ASSERT_TRUE(again.ok());
  const auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  EXPECT_TRUE(same(again->skin.positions, skin().positions));
  EXPECT_TRUE(same(again->skin.normals, skin().normals));
  EXPECT_TRUE(same(again->skin.indices, skin().indices));
  EXPECT_TRUE(same(again->skin.joints, skin().joints));
  EXPECT_TRUE(same(again->skin.weights, skin().weights));
  EXPECT_TRUE(same(again->skeleton.inverse_bind, avatar().skeleton.inverse_bind));
}

TEST(DefaultAvatarBuild, OtherProportionsStayAClosedManifold) {
  DefaultAvatarOptions options;
  options.height = 1.55f;
  options.girth = 1.2f;
  options.arm_angle_deg = 40.0f;
  options.target_vertices = 6000;
  const Result<AvatarModel> a = makeDefaultAvatar(options);
  ASSERT_TRUE(a.ok()) << a.error().message;
  EXPECT_EQ(a->skin.vertexCount(), 6000);
  const test::Topology topo = test::analyseTopology(a->skin.positions, a->skin.indices);
  EXPECT_TRUE(topo.edges_paired);
  EXPECT_EQ(topo.nonmanifold_vertices, 0);
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.euler, 2);
  EXPECT_NEAR(computeBounds(a->skin.positions).max.y, 1.55f, 0.01f);
  EXPECT_GT(enclosedVolume(a->skin.positions, a->skin.indices), 0.0);
}

TEST(DefaultAvatarBuild, RejectsOptionsOutOfRange) {
  DefaultAvatarOptions options;
  options.height = 5.0f;
  Result<AvatarModel> a = makeDefaultAvatar(options);
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.error().message.find("height"), std::string::npos) << a.error().message;
  options = {};
  options.target_vertices = 100;
  a = makeDefaultAvatar(options);
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.error().message.find("target_vertices"), std::string::npos) << a.error().message;
}

}  // namespace
}  // namespace vistel
