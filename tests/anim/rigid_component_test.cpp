// The spine lattice (ffd) and rigid + slerp skinning beside LBS and DQS (DESIGN.md §4,
// issue 25 item 11): rest posture, smooth torso bending, rigid limbs, no candy wrapper,
// and the fallback when a skeleton has no spine.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"
#include "common/anim/skinning_rig.hpp"

namespace vistel {
namespace {

constexpr SkinningMethod kAllMethods[] = {SkinningMethod::kLinear, SkinningMethod::kDualQuaternion,
                                          SkinningMethod::kSpineFfd, SkinningMethod::kRigidSlerp};

struct Model {
  Skeleton skeleton;
  SkinMesh mesh;
};

// A closed tube along `axis` from a to b (rings x sides, a centre vertex on each cap), its
// weights from weigh(vertex position) as (joint, weight) pairs over `k` slots.
template <typename Weigh>
void addTube(SkinMesh& m, float a, float b, int axis, float radius, int rings, int sides,
             Weigh weigh) {
  const auto base = static_cast<std::uint32_t>(m.positions.size());
  const auto k = static_cast<std::size_t>(m.influences);
  const auto add_vertex = [&](glm::vec3 p, glm::vec3 n) {
    m.positions.push_back(p);
    m.normals.push_back(n);
    const std::vector<std::pair<int, float>> w = weigh(p);
    for (std::size_t s = 0; s < k; ++s) {
      m.joints.push_back(s < w.size() ? static_cast<std::uint16_t>(w[s].first) : 0);
      m.weights.push_back(s < w.size() ? w[s].second : 0.0f);
    }
  };
  const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
  for (int i = 0; i <= rings; ++i) {
    const float x = a + (b - a) * static_cast<float>(i) / static_cast<float>(rings);
    for (int s = 0; s < sides; ++s) {
      const float t =
          2.0f * std::numbers::pi_v<float> * static_cast<float>(s) / static_cast<float>(sides);
      glm::vec3 n(0.0f);
      n[u_axis] = std::cos(t);
      n[v_axis] = std::sin(t);
      glm::vec3 p = radius * n;
      p[axis] = x;
      add_vertex(p, n);
    }
  }
  const auto ring = [&](int i, int s) {
    return base + static_cast<std::uint32_t>(i * sides + (s % sides));
  };
  for (int i = 0; i < rings; ++i) {
    for (int s = 0; s < sides; ++s) {
      m.indices.insert(m.indices.end(), {ring(i, s), ring(i, s + 1), ring(i + 1, s + 1)});
      m.indices.insert(m.indices.end(), {ring(i, s), ring(i + 1, s + 1), ring(i + 1, s)});
    }
  }
  glm::vec3 pa(0.0f), pb(0.0f), na(0.0f), nb(0.0f);
  pa[axis] = a;
  pb[axis] = b;
  na[axis] = -1.0f;
  nb[axis] = 1.0f;
  const auto ca = static_cast<std::uint32_t>(m.positions.size());
  add_vertex(pa, na);
  const auto cb = static_cast<std::uint32_t>(m.positions.size());
  add_vertex(pb, nb);
  for (int s = 0; s < sides; ++s) {
    m.indices.insert(m.indices.end(), {ca, ring(0, s + 1), ring(0, s)});
    m.indices.insert(m.indices.end(), {cb, ring(rings, s), ring(rings, s + 1)});
  }
}

// Weights blending two joints linearly over [centre - half, centre + half].
std::vector<std::pair<int, float>> blend(float x, float centre, float half, int lo, int hi) {
  const float t = std::clamp((x - (centre - half)) / (2.0f * half), 0.0f, 1.0f);
  return {{lo, 1.0f - t}, {hi, t}};
}

// A torso along +Y: hips (root, y = 1.0), spine 1.1, chest 1.2, upper_chest 1.3, neck 1.42,
// head 1.52 (the canonical names), and an unweighted thigh. A tube of radius 0.13 from 0.95
// to 1.5, each bone's part weighted to it, blended over +-3 cm around each joint; the top
// blends neck into head.
Model makeTorso() {
  Model t;
  Skeleton& s = t.skeleton;
  s.names = {"hips", "spine", "chest", "upper_chest", "neck", "head", "l_thigh"};
  s.parents = {kNoParent, 0, 1, 2, 3, 4, 0};
  s.rest_local.resize(s.names.size());
  s.rest_local[0].translation = glm::vec3(0.0f, 1.0f, 0.0f);
  s.rest_local[1].translation = glm::vec3(0.0f, 0.1f, 0.0f);
  s.rest_local[2].translation = glm::vec3(0.0f, 0.1f, 0.0f);
  s.rest_local[3].translation = glm::vec3(0.0f, 0.1f, 0.0f);
  s.rest_local[4].translation = glm::vec3(0.0f, 0.12f, 0.0f);
  s.rest_local[5].translation = glm::vec3(0.0f, 0.1f, 0.0f);
  s.rest_local[6].translation = glm::vec3(0.1f, -0.05f, 0.0f);
  computeInverseBind(s);
  t.mesh.influences = 2;
  const float joints_y[] = {1.0f, 1.1f, 1.2f, 1.3f, 1.42f, 1.52f};
  addTube(t.mesh, 0.95f, 1.5f, 1, 0.13f, 55, 32, [&](glm::vec3 p) {
    if (p.y > 1.46f) return blend(p.y, 1.48f, 0.02f, 4, 5);  // neck into head
    int j = 0;
    while (j < 4 && p.y > joints_y[j + 1]) ++j;  // the bone the point is on (0..4)
    if (j < 4 && p.y > 0.5f * (joints_y[j] + joints_y[j + 1])) {
      return blend(p.y, joints_y[j + 1], 0.03f, j, j + 1);
    }
    return j > 0 ? blend(p.y, joints_y[j], 0.03f, j - 1, j)
                 : std::vector<std::pair<int, float>>{{0, 1.0f}};
  });
  return t;
}

// The arm of skinning_test: upper (root) along +X to the elbow at L, fore from L to 2L,
// blended over +-6 cm around the elbow.
Model makeRigArm(float length = 0.3f, float radius = 0.04f) {
  Model arm;
  Skeleton& s = arm.skeleton;
  s.names = {"upper", "fore"};
  s.parents = {kNoParent, 0};
  s.rest_local.resize(2);
  s.rest_local[1].translation = glm::vec3(length, 0.0f, 0.0f);
  computeInverseBind(s);
  arm.mesh.influences = 2;
  addTube(arm.mesh, 0.0f, 2.0f * length, 0, radius, 60, 24,
          [&](glm::vec3 p) { return blend(p.x, length, 0.06f, 0, 1); });
  return arm;
}

struct RigPosed {
  std::vector<glm::vec3> positions, normals;
  SkinningRig rig;
  RigFrame frame;
};

RigPosed pose(const Model& m, const Posture& posture, SkinningMethod method) {
  const auto n = static_cast<std::size_t>(m.skeleton.jointCount());
  std::vector<glm::mat4> model(n), skin(n);
  std::vector<DualQuat> dq(n);
  poseSkeleton(m.skeleton, posture, model);
  skinningMatrices(m.skeleton, model, skin);
  RigPosed out;
  out.rig = makeSkinningRig(m.skeleton, m.mesh, method);
  out.positions.resize(m.mesh.positions.size());
  out.normals.resize(m.mesh.positions.size());
  out.frame = makeRigFrame(out.rig);
  prepareRigFrame(out.rig, skin, dq, out.frame);
  skinRigRange(m.mesh, out.rig, skin, dq, out.frame, 0, out.positions, out.normals);
  return out;
}

// Forward bend: spine, chest and upper_chest each turned by `angle` about +X.
Posture bent(const Skeleton& s, float angle) {
  Posture p = restPosture(s);
  for (int j = 1; j <= 3; ++j) {
    p.rotations[static_cast<std::size_t>(j)] = glm::angleAxis(angle, glm::vec3(1, 0, 0));
  }
  return p;
}

// Smallest distance from p to a polyline of dense samples.
float distanceTo(std::span<const glm::vec3> curve, const glm::vec3& p) {
  float best = std::numeric_limits<float>::max();
  for (std::size_t i = 0; i + 1 < curve.size(); ++i) {
    const glm::vec3 d = curve[i + 1] - curve[i];
    const float len2 = glm::dot(d, d);
    const float t = len2 > 0.0f ? std::clamp(glm::dot(p - curve[i], d) / len2, 0.0f, 1.0f) : 0.0f;
    best = std::min(best, glm::length(p - (curve[i] + t * d)));
  }
  return best;
}

// Smallest ratio of a triangle's posed area to its rest area.
double minAreaRatio(const SkinMesh& m, std::span<const glm::vec3> posed) {
  double worst = std::numeric_limits<double>::max();
  for (std::size_t f = 0; f + 2 < m.indices.size(); f += 3) {
    const auto area = [&](std::span<const glm::vec3> p) {
      const glm::vec3 a = p[m.indices[f]], b = p[m.indices[f + 1]], c = p[m.indices[f + 2]];
      return 0.5 * static_cast<double>(glm::length(glm::cross(b - a, c - a)));
    };
    const double rest = area(m.positions);
    if (rest > 1e-9) worst = std::min(worst, area(posed) / rest);
  }
  return worst;
}

TEST(RigidComponent, MethodNamesRoundTrip) {
  for (SkinningMethod m : kAllMethods) {
    EXPECT_EQ(parseSkinningMethod(skinningMethodName(m)), m);
  }
  EXPECT_EQ(parseSkinningMethod("slerp"), SkinningMethod::kRigidSlerp);
  EXPECT_EQ(parseSkinningMethod("ffd"), SkinningMethod::kSpineFfd);
  EXPECT_FALSE(parseSkinningMethod("DQS").has_value());
  EXPECT_FALSE(parseSkinningMethod("").has_value());
}

TEST(RigidComponent, FixturesAreValid) {
  for (const Model& m : {makeTorso(), makeRigArm()}) {
    ASSERT_TRUE(validateSkeleton(m.skeleton).ok());
    const Status s = validateSkinMesh(m.mesh, m.skeleton.jointCount());
    ASSERT_TRUE(s.ok()) << s.error().message;
    EXPECT_GT(enclosedVolume(m.mesh.positions, m.mesh.indices), 0.0);
  }
}

TEST(RigidComponent, RestPostureGivesRestPositionsForEveryMethod) {
  Model torso = makeTorso();
  Model arm = makeRigArm();
  // Non-identity rest rotations and an offset root make it meaningful.
  torso.skeleton.rest_local[0].rotation = glm::angleAxis(0.5f, glm::normalize(glm::vec3(1, 2, 3)));
  torso.skeleton.rest_local[2].rotation = glm::angleAxis(-0.3f, glm::vec3(0, 0, 1));
  computeInverseBind(torso.skeleton);
  arm.skeleton.rest_local[0].rotation = glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 2, 3)));
  arm.skeleton.rest_local[0].translation = glm::vec3(0.1f, 0.9f, -0.2f);
  arm.skeleton.rest_local[1].rotation = glm::angleAxis(-0.4f, glm::vec3(0, 0, 1));
  computeInverseBind(arm.skeleton);
  for (const Model* m : {&torso, &arm}) {
    for (SkinningMethod method : kAllMethods) {
      const RigPosed posed = pose(*m, restPosture(m->skeleton), method);
      for (std::size_t v = 0; v < posed.positions.size(); ++v) {
        ASSERT_LT(glm::length(posed.positions[v] - m->mesh.positions[v]), 2e-6f)
            << skinningMethodName(method) << " vertex " << v;
        ASSERT_LT(glm::length(posed.normals[v] - m->mesh.normals[v]), 1e-5f)
            << skinningMethodName(method) << " vertex " << v;
      }
    }
  }
}

TEST(RigidComponent, WholeBodyMotionIsRigidForEveryMethod) {
  const Model torso = makeTorso();
  Posture p = restPosture(torso.skeleton);
  const glm::quat turn = glm::angleAxis(1.1f, glm::normalize(glm::vec3(0.2f, 1.0f, -0.4f)));
  p.rotations[0] = turn;
  p.root_translation = glm::vec3(0.4f, 1.2f, -2.0f);
  for (SkinningMethod method : kAllMethods) {
    const RigPosed posed = pose(torso, p, method);
    for (std::size_t v = 0; v < posed.positions.size(); ++v) {
      const glm::vec3 expected =
          turn * (torso.mesh.positions[v] - glm::vec3(0, 1, 0)) + p.root_translation;
      ASSERT_LT(glm::length(posed.positions[v] - expected), 1e-5f)
          << skinningMethodName(method) << " vertex " << v;
    }
  }
}

TEST(RigidComponent, SpineLatticeFindsTheChainAndTheTorso) {
  const Model torso = makeTorso();
  const SpineLattice lattice = buildSpineLattice(torso.skeleton, torso.mesh);
  ASSERT_FALSE(lattice.empty()) << lattice.warning;
  EXPECT_EQ(lattice.chain, (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(lattice.end_joint, 5);
  EXPECT_TRUE(lattice.warning.empty());
  // Every vertex touches the chain; the top blends into the head (partly torso).
  EXPECT_EQ(lattice.torso_vertices, torso.mesh.vertexCount());
  const auto partial = std::count_if(lattice.torso.begin(), lattice.torso.end(),
                                     [](float t) { return t > 0.0f && t < 1.0f; });
  EXPECT_GT(partial, 0);
  // An explicit head gives the same chain.
  EXPECT_EQ(buildSpineLattice(torso.skeleton, torso.mesh, 5).chain, lattice.chain);
}

TEST(RigidComponent, SpineLatticeBendsTheTorsoSmoothly) {
  const Model torso = makeTorso();
  const Posture p = bent(torso.skeleton, 0.5f);  // 3 x ~29 degrees forward
  const RigPosed ffd = pose(torso, p, SkinningMethod::kSpineFfd);
  const RigPosed lbs = pose(torso, p, SkinningMethod::kLinear);
  const RigPosed dqs = pose(torso, p, SkinningMethod::kDualQuaternion);
  ASSERT_EQ(ffd.rig.method, SkinningMethod::kSpineFfd) << ffd.rig.warning;

  // The rest and posed spine curves, densely sampled.
  const int n = static_cast<int>(ffd.rig.lattice.chain.size());
  SpineLatticePose rest_pose;
  const std::vector<DualQuat> identity(torso.skeleton.names.size());
  poseSpineLattice(ffd.rig.lattice, identity, rest_pose);
  std::vector<glm::vec3> rest_curve, posed_curve;
  for (int i = 0; i <= 100 * n; ++i) {
    const float u = static_cast<float>(i) / 100.0f;
    rest_curve.push_back(spineCurvePoint(rest_pose, u));
    posed_curve.push_back(spineCurvePoint(ffd.frame.lattice, u));
  }
  // No torso vertex farther from the posed spine than from the rest spine (+1 mm).
  float worst = -1.0f;
  for (std::size_t v = 0; v < ffd.positions.size(); ++v) {
    if (ffd.rig.lattice.torso[v] < 1.0f) continue;
    const float rest_d = distanceTo(rest_curve, torso.mesh.positions[v]);
    const float posed_d = distanceTo(posed_curve, ffd.positions[v]);
    worst = std::max(worst, posed_d - rest_d);
    ASSERT_LE(posed_d, rest_d + 1e-3f) << "vertex " << v;
  }
  EXPECT_GE(worst, -1e-3f);
  // Volume: the sweep keeps it better than LBS.
  const auto volume = [&](const RigPosed& q) {
    return enclosedVolume(q.positions, torso.mesh.indices);
  };
  const double rest = enclosedVolume(torso.mesh.positions, torso.mesh.indices);
  const double d_ffd = std::abs(volume(ffd) - rest) / rest;
  const double d_lbs = std::abs(volume(lbs) - rest) / rest;
  const double d_dqs = std::abs(volume(dqs) - rest) / rest;
  EXPECT_LT(d_ffd, d_lbs);
  EXPECT_LT(d_ffd, 0.01);
  // Smooth: no triangle squeezed (the inside of the bend) as much as by LBS or DQS.
  const double a_ffd = minAreaRatio(torso.mesh, ffd.positions);
  const double a_lbs = minAreaRatio(torso.mesh, lbs.positions);
  const double a_dqs = minAreaRatio(torso.mesh, dqs.positions);
  EXPECT_GT(a_ffd, a_lbs);
  EXPECT_GT(a_ffd, a_dqs);
  RecordProperty("volume_change_ffd", std::to_string(d_ffd));
  std::printf(
      "bend: volume change ffd %.4f lbs %.4f dqs %.4f; min area ratio ffd %.3f lbs %.3f "
      "dqs %.3f\n",
      d_ffd, d_lbs, d_dqs, a_ffd, a_lbs, a_dqs);
}

TEST(RigidComponent, SpineLatticeLeavesVerticesOffTheChainToDualQuaternions) {
  // An arm on the chest: its vertices have no chain weight and must be exactly DQS.
  Model torso = makeTorso();
  torso.skeleton.names.push_back("l_upperarm");
  torso.skeleton.parents.push_back(3);
  Transform arm_rest;
  arm_rest.translation = glm::vec3(0.18f, 0.05f, 0.0f);
  torso.skeleton.rest_local.push_back(arm_rest);
  computeInverseBind(torso.skeleton);
  const auto first_arm = torso.mesh.positions.size();
  addTube(torso.mesh, 0.2f, 0.5f, 0, 0.04f, 10, 12, [](glm::vec3) {
    return std::vector<std::pair<int, float>>{{7, 1.0f}};
  });
  for (std::size_t v = first_arm; v < torso.mesh.positions.size(); ++v) {
    torso.mesh.positions[v].y += 1.35f;
  }
  Posture p = bent(torso.skeleton, 0.3f);
  p.rotations[7] = glm::angleAxis(0.8f, glm::vec3(0, 0, 1));
  const RigPosed ffd = pose(torso, p, SkinningMethod::kSpineFfd);
  const RigPosed dqs = pose(torso, p, SkinningMethod::kDualQuaternion);
  for (std::size_t v = first_arm; v < torso.mesh.positions.size(); ++v) {
    ASSERT_EQ(ffd.positions[v], dqs.positions[v]) << "vertex " << v;
    ASSERT_EQ(ffd.normals[v], dqs.normals[v]) << "vertex " << v;
  }
}

TEST(RigidComponent, SlerpKeepsSingleBoneVerticesRigid) {
  const Model arm = makeRigArm();
  Posture p = restPosture(arm.skeleton);
  p.rotations[0] = glm::angleAxis(0.8f, glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f)));
  p.rotations[1] = glm::angleAxis(1.2f, glm::normalize(glm::vec3(0.0f, 0.4f, 1.0f)));
  p.root_translation = glm::vec3(0.5f, 1.0f, 0.0f);
  std::vector<glm::mat4> model(2), skin(2);
  poseSkeleton(arm.skeleton, p, model);
  skinningMatrices(arm.skeleton, model, skin);
  const RigPosed slerp = pose(arm, p, SkinningMethod::kRigidSlerp);
  int rigid = 0;
  for (std::size_t v = 0; v < slerp.positions.size(); ++v) {
    for (std::size_t s = 0; s < 2; ++s) {
      if (arm.mesh.weights[v * 2 + s] != 1.0f) continue;
      const glm::mat4& m = skin[arm.mesh.joints[v * 2 + s]];
      const glm::vec3 expected(m * glm::vec4(arm.mesh.positions[v], 1.0f));
      ASSERT_LT(glm::length(slerp.positions[v] - expected), 2e-6f) << "vertex " << v;
      ASSERT_LT(glm::length(slerp.normals[v] - glm::mat3(m) * arm.mesh.normals[v]), 1e-5f);
      ++rigid;
    }
  }
  EXPECT_GT(rigid, 100);
}

TEST(RigidComponent, SlerpHasNoCandyWrapperAtAHalfTurnTwist) {
  const Model arm = makeRigArm();
  Posture p = restPosture(arm.skeleton);
  p.rotations[1] = glm::angleAxis(std::numbers::pi_v<float>, glm::vec3(1, 0, 0));
  const RigPosed lbs = pose(arm, p, SkinningMethod::kLinear);
  const RigPosed slerp = pose(arm, p, SkinningMethod::kRigidSlerp);
  // Radius about the arm's axis of every ring vertex (the cap centres lie on it).
  float lbs_min = 1.0f, slerp_min = 1.0f, slerp_max = 0.0f;
  for (std::size_t v = 0; v + 2 < arm.mesh.positions.size(); ++v) {
    const auto radius = [](const glm::vec3& q) { return std::hypot(q.y, q.z); };
    lbs_min = std::min(lbs_min, radius(lbs.positions[v]));
    slerp_min = std::min(slerp_min, radius(slerp.positions[v]));
    slerp_max = std::max(slerp_max, radius(slerp.positions[v]));
    // The axial position does not move either.
    ASSERT_NEAR(slerp.positions[v].x, arm.mesh.positions[v].x, 1e-5f) << "vertex " << v;
  }
  EXPECT_LT(lbs_min, 0.1f * 0.04f) << "LBS should collapse the elbow at a half-turn twist";
  EXPECT_NEAR(slerp_min, 0.04f, 1e-5f);
  EXPECT_NEAR(slerp_max, 0.04f, 1e-5f);
  const double rest = enclosedVolume(arm.mesh.positions, arm.mesh.indices);
  EXPECT_NEAR(enclosedVolume(slerp.positions, arm.mesh.indices), rest, 0.002 * rest);
  EXPECT_LT(enclosedVolume(lbs.positions, arm.mesh.indices), 0.95 * rest);
}

TEST(RigidComponent, SlerpRoundsABentElbowLikeDualQuaternions) {
  const Model arm = makeRigArm();
  Posture p = restPosture(arm.skeleton);
  p.rotations[1] = glm::angleAxis(1.6f, glm::vec3(0, 0, 1));
  const double rest = enclosedVolume(arm.mesh.positions, arm.mesh.indices);
  const auto change = [&](SkinningMethod m) {
    return std::abs(enclosedVolume(pose(arm, p, m).positions, arm.mesh.indices) - rest) / rest;
  };
  EXPECT_LT(change(SkinningMethod::kRigidSlerp), change(SkinningMethod::kLinear));
}

TEST(RigidComponent, NoSpineChainFallsBackToDualQuaternionsWithAMessage) {
  // The arm has no head; a skeleton whose head has a single skinned ancestor has no chain.
  const Model arm = makeRigArm();
  Posture p = restPosture(arm.skeleton);
  p.rotations[1] = glm::angleAxis(1.0f, glm::vec3(0, 0, 1));
  const RigPosed ffd = pose(arm, p, SkinningMethod::kSpineFfd);
  const RigPosed dqs = pose(arm, p, SkinningMethod::kDualQuaternion);
  EXPECT_EQ(ffd.rig.requested, SkinningMethod::kSpineFfd);
  EXPECT_EQ(ffd.rig.method, SkinningMethod::kDualQuaternion);
  EXPECT_NE(ffd.rig.warning.find("falls back to dqs"), std::string::npos) << ffd.rig.warning;
  EXPECT_NE(ffd.rig.warning.find("no head joint"), std::string::npos) << ffd.rig.warning;
  EXPECT_EQ(ffd.positions, dqs.positions);
  EXPECT_EQ(ffd.normals, dqs.normals);

  Model short_neck = makeRigArm();
  short_neck.skeleton.names = {"pelvis", "Head"};
  const SpineLattice lattice = buildSpineLattice(short_neck.skeleton, short_neck.mesh);
  EXPECT_TRUE(lattice.empty());
  EXPECT_NE(lattice.warning.find("'Head'"), std::string::npos) << lattice.warning;
  EXPECT_NE(lattice.warning.find("needs 2"), std::string::npos) << lattice.warning;
  // The other methods never fall back.
  for (SkinningMethod m : kAllMethods) {
    if (m == SkinningMethod::kSpineFfd) continue;
    const SkinningRig rig = makeSkinningRig(arm.skeleton, arm.mesh, m);
    EXPECT_EQ(rig.method, m);
    EXPECT_TRUE(rig.warning.empty());
  }
}

TEST(RigidComponent, RigMatchesTheLinearAndDualQuaternionKernelsBitForBit) {
  const Model torso = makeTorso();
  const Posture p = bent(torso.skeleton, 0.4f);
  const auto n = static_cast<std::size_t>(torso.skeleton.jointCount());
  std::vector<glm::mat4> model(n), skin(n);
  std::vector<DualQuat> dq(n);
  poseSkeleton(torso.skeleton, p, model);
  skinningMatrices(torso.skeleton, model, skin);
  const std::size_t nv = torso.mesh.positions.size();
  for (SkinningMethod m : {SkinningMethod::kLinear, SkinningMethod::kDualQuaternion}) {
    std::vector<glm::vec3> a(nv), an(nv), b(nv), bn(nv);
    skinMesh(torso.mesh, m, skin, dq, a, an);
    const SkinningRig rig = makeSkinningRig(torso.skeleton, torso.mesh, m);
    RigFrame frame = makeRigFrame(rig);
    skinMesh(torso.mesh, rig, skin, dq, frame, b, bn);
    EXPECT_EQ(a, b) << skinningMethodName(m);
    EXPECT_EQ(an, bn) << skinningMethodName(m);
  }
}

TEST(RigidComponent, RangesGiveTheSameVerticesAsTheWholeMesh) {
  const Model torso = makeTorso();
  const Posture p = bent(torso.skeleton, 0.4f);
  const auto n = static_cast<std::size_t>(torso.skeleton.jointCount());
  std::vector<glm::mat4> model(n), skin(n);
  poseSkeleton(torso.skeleton, p, model);
  skinningMatrices(torso.skeleton, model, skin);
  const std::size_t nv = torso.mesh.positions.size();
  for (SkinningMethod m : {SkinningMethod::kSpineFfd, SkinningMethod::kRigidSlerp}) {
    const SkinningRig rig = makeSkinningRig(torso.skeleton, torso.mesh, m);
    std::vector<DualQuat> dq(n);
    RigFrame frame = makeRigFrame(rig);
    prepareRigFrame(rig, skin, dq, frame);
    std::vector<glm::vec3> whole(nv), whole_n(nv), parts(nv), parts_n(nv);
    skinRigRange(torso.mesh, rig, skin, dq, frame, 0, whole, whole_n);
    for (std::size_t first = 0; first < nv; first += 97) {
      const std::size_t count = std::min<std::size_t>(97, nv - first);
      skinRigRange(torso.mesh, rig, skin, dq, frame, first, std::span(parts).subspan(first, count),
                   std::span(parts_n).subspan(first, count));
    }
    EXPECT_EQ(whole, parts) << skinningMethodName(m);
    EXPECT_EQ(whole_n, parts_n) << skinningMethodName(m);
  }
}

}  // namespace
}  // namespace vistel
