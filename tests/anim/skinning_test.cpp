// Invariants of forward kinematics and the rigid component (DESIGN.md §4).
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"

namespace vistel {
namespace {

// A two-bone "arm" along +X (upper arm 0..L, forearm L..2L) skinned by a closed tube of
// radius r, weights blending linearly across the elbow over +-blend.
struct Arm {
  Skeleton skeleton;
  SkinMesh mesh;
};

Arm makeArm(float length = 0.3f, float radius = 0.04f, float blend = 0.06f, int rings = 60,
            int sides = 24) {
  Arm arm;
  Skeleton& s = arm.skeleton;
  s.names = {"upper", "fore"};
  s.parents = {kNoParent, 0};
  s.rest_local.resize(2);
  s.rest_local[1].translation = glm::vec3(length, 0.0f, 0.0f);
  computeInverseBind(s);

  SkinMesh& m = arm.mesh;
  m.influences = 2;
  auto add_vertex = [&](glm::vec3 p, glm::vec3 n) {
    m.positions.push_back(p);
    m.normals.push_back(n);
    const float t = std::clamp((p.x - (length - blend)) / (2.0f * blend), 0.0f, 1.0f);
    m.joints.insert(m.joints.end(), {0, 1});
    m.weights.insert(m.weights.end(), {1.0f - t, t});
  };
  for (int i = 0; i <= rings; ++i) {
    const float x = 2.0f * length * static_cast<float>(i) / static_cast<float>(rings);
    for (int k = 0; k < sides; ++k) {
      const float a =
          2.0f * std::numbers::pi_v<float> * static_cast<float>(k) / static_cast<float>(sides);
      const glm::vec3 n(0.0f, std::cos(a), std::sin(a));
      add_vertex(glm::vec3(x, 0.0f, 0.0f) + radius * n, n);
    }
  }
  const auto ring = [&](int i, int k) {
    return static_cast<std::uint32_t>(i * sides + (k % sides));
  };
  for (int i = 0; i < rings; ++i) {
    for (int k = 0; k < sides; ++k) {
      m.indices.insert(m.indices.end(), {ring(i, k), ring(i, k + 1), ring(i + 1, k + 1)});
      m.indices.insert(m.indices.end(), {ring(i, k), ring(i + 1, k + 1), ring(i + 1, k)});
    }
  }
  // Caps: a centre vertex at each end.
  const auto c0 = static_cast<std::uint32_t>(m.positions.size());
  add_vertex(glm::vec3(0.0f), glm::vec3(-1, 0, 0));
  const auto c1 = static_cast<std::uint32_t>(m.positions.size());
  add_vertex(glm::vec3(2.0f * length, 0.0f, 0.0f), glm::vec3(1, 0, 0));
  for (int k = 0; k < sides; ++k) {
    m.indices.insert(m.indices.end(), {c0, ring(0, k + 1), ring(0, k)});
    m.indices.insert(m.indices.end(), {c1, ring(rings, k), ring(rings, k + 1)});
  }
  return arm;
}

struct Posed {
  std::vector<glm::vec3> positions, normals;
};

Posed pose(const Arm& arm, const Posture& posture, SkinningMethod method) {
  const auto n = static_cast<std::size_t>(arm.skeleton.jointCount());
  std::vector<glm::mat4> model(n), skin(n);
  std::vector<DualQuat> dq(n);
  poseSkeleton(arm.skeleton, posture, model);
  skinningMatrices(arm.skeleton, model, skin);
  Posed out;
  out.positions.resize(arm.mesh.positions.size());
  out.normals.resize(arm.mesh.positions.size());
  skinMesh(arm.mesh, method, skin, dq, out.positions, out.normals);
  return out;
}

TEST(Skinning, ArmFixtureIsValidAndClosed) {
  const Arm arm = makeArm();
  ASSERT_TRUE(validateSkeleton(arm.skeleton).ok());
  ASSERT_TRUE(validateSkinMesh(arm.mesh, 2).ok()) << validateSkinMesh(arm.mesh, 2).error().message;
  // A 24-sided prism: cross-section (n/2) r^2 sin(2 pi / n), length 0.6 m.
  const double expected = 12.0 * 0.04 * 0.04 * std::sin(2.0 * std::numbers::pi / 24.0) * 0.6;
  EXPECT_NEAR(enclosedVolume(arm.mesh.positions, arm.mesh.indices), expected, 1e-4 * expected);
}

TEST(Skinning, RestPostureReproducesPrototypeMesh) {
  Arm arm = makeArm();
  // A non-identity rest rotation and an offset root make the test meaningful.
  arm.skeleton.rest_local[0].rotation = glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 2, 3)));
  arm.skeleton.rest_local[0].translation = glm::vec3(0.1f, 0.9f, -0.2f);
  arm.skeleton.rest_local[1].rotation = glm::angleAxis(-0.4f, glm::vec3(0, 0, 1));
  computeInverseBind(arm.skeleton);
  for (SkinningMethod method : {SkinningMethod::kLinear, SkinningMethod::kDualQuaternion}) {
    const Posed posed = pose(arm, restPosture(arm.skeleton), method);
    for (std::size_t v = 0; v < posed.positions.size(); ++v) {
      ASSERT_LT(glm::length(posed.positions[v] - arm.mesh.positions[v]), 1e-6f) << "vertex " << v;
      ASSERT_LT(glm::length(posed.normals[v] - arm.mesh.normals[v]), 1e-5f) << "vertex " << v;
    }
  }
}

TEST(Skinning, ForwardKinematicsComposesParents) {
  const Arm arm = makeArm();
  Posture p = restPosture(arm.skeleton);
  p.rotations[0] = glm::angleAxis(std::numbers::pi_v<float> / 2.0f, glm::vec3(0, 0, 1));
  p.root_translation = glm::vec3(1.0f, 2.0f, 3.0f);
  std::vector<glm::mat4> model(2);
  poseSkeleton(arm.skeleton, p, model);
  // The elbow, 0.3 m along the upper arm's +X, is rotated to +Y.
  const glm::vec3 elbow(model[1][3]);
  EXPECT_NEAR(glm::length(elbow - glm::vec3(1.0f, 2.3f, 3.0f)), 0.0f, 1e-6f);
}

TEST(Skinning, RigidlyMovedVerticesAgreeBetweenMethods) {
  const Arm arm = makeArm();
  Posture p = restPosture(arm.skeleton);
  p.rotations[0] = glm::angleAxis(0.8f, glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)));
  p.root_translation = glm::vec3(0.5f, 1.0f, 0.0f);
  const Posed lbs = pose(arm, p, SkinningMethod::kLinear);
  const Posed dqs = pose(arm, p, SkinningMethod::kDualQuaternion);
  for (std::size_t v = 0; v < lbs.positions.size(); ++v) {
    ASSERT_LT(glm::length(lbs.positions[v] - dqs.positions[v]), 1e-5f) << "vertex " << v;
  }
}

TEST(Skinning, DualQuaternionKeepsMoreVolumeThanLinearOnForearmTwist) {
  const Arm arm = makeArm();
  Posture p = restPosture(arm.skeleton);
  p.rotations[1] = glm::angleAxis(std::numbers::pi_v<float> / 2.0f, glm::vec3(1, 0, 0));
  const double rest = enclosedVolume(arm.mesh.positions, arm.mesh.indices);
  const Posed lbs = pose(arm, p, SkinningMethod::kLinear);
  const Posed dqs = pose(arm, p, SkinningMethod::kDualQuaternion);
  const double v_lbs = enclosedVolume(lbs.positions, arm.mesh.indices);
  const double v_dqs = enclosedVolume(dqs.positions, arm.mesh.indices);
  // LBS collapses the twisted region (candy wrapper); DQS rotates it rigidly.
  EXPECT_LT(v_lbs, rest * 0.99) << "LBS should lose volume on a 90 degree twist";
  EXPECT_GT(v_dqs, v_lbs);
  EXPECT_NEAR(v_dqs, rest, rest * 0.005);
}

TEST(Skinning, ValidationRejectsBadWeightsAndIndices) {
  Arm arm = makeArm();
  arm.mesh.weights[0] = 0.5f;  // vertex 0 now sums to 0.5
  EXPECT_FALSE(validateSkinMesh(arm.mesh, 2).ok());
  arm = makeArm();
  arm.mesh.indices[5] = 1000000;
  const Status s = validateSkinMesh(arm.mesh, 2);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("triangle 1"), std::string::npos) << s.error().message;
  arm = makeArm();
  arm.skeleton.parents[1] = 1;
  EXPECT_FALSE(validateSkeleton(arm.skeleton).ok());
}

}  // namespace
}  // namespace vistel
