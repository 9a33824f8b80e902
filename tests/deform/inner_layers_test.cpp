// Inner layers (common/deform/inner_layers.hpp, issue 25 item 5): the default avatar with two
// eyeballs and a tongue added inside its head, skinned to the head bone. Detection finds
// exactly those three components (and none on the plain default avatar nor on the shared
// MakeHuman body); the built model carries them rigidly (also through the codec); and with a
// rigid ball pressed into the face while the head nods, every inner vertex stays exactly at
// its skinned position, never in contact, while the outer skin dents.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/skeleton.hpp"
#include "common/deform/implicit_codec.hpp"
#include "common/deform/inner_layers.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "offline/synth/default_avatar.hpp"
#include "tests/deform/fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// Appends a closed UV sphere (outward triangles) skinned wholly to `joint`; returns its first
// vertex.
std::uint32_t addSphere(SkinMesh& m, const glm::vec3& c, float r, int joint) {
  const auto first = static_cast<std::uint32_t>(m.positions.size());
  const auto k = static_cast<std::size_t>(m.influences);
  const auto add = [&](const glm::vec3& n) {
    m.positions.push_back(c + r * n);
    m.normals.push_back(n);
    for (std::size_t s = 0; s < k; ++s) {
      m.joints.push_back(static_cast<std::uint16_t>(joint));
      m.weights.push_back(s == 0 ? 1.0f : 0.0f);
    }
  };
  constexpr int kRings = 8, kSides = 12;
  add({0.0f, 1.0f, 0.0f});  // top
  for (int i = 1; i < kRings; ++i) {
    const float th = static_cast<float>(M_PI) * static_cast<float>(i) / kRings;
    for (int j = 0; j < kSides; ++j) {
      const float ph = 2.0f * static_cast<float>(M_PI) * static_cast<float>(j) / kSides;
      add({std::sin(th) * std::cos(ph), std::cos(th), -std::sin(th) * std::sin(ph)});
    }
  }
  add({0.0f, -1.0f, 0.0f});  // bottom
  const auto ring = [&](int i, int j) {
    return first + 1 + static_cast<std::uint32_t>((i - 1) * kSides + (j % kSides));
  };
  const std::uint32_t top = first, bottom = first + 1 + (kRings - 1) * kSides;
  for (int j = 0; j < kSides; ++j) {
    m.indices.insert(m.indices.end(), {top, ring(1, j), ring(1, j + 1)});
    m.indices.insert(m.indices.end(), {bottom, ring(kRings - 1, j + 1), ring(kRings - 1, j)});
    for (int i = 1; i + 1 < kRings; ++i) {
      m.indices.insert(m.indices.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.indices.insert(m.indices.end(), {ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
  return first;
}

// Appends a closed box (8 corners, outward triangles) skinned wholly to `joint`.
std::uint32_t addBox(SkinMesh& m, const glm::vec3& lo, const glm::vec3& hi, int joint) {
  const auto first = static_cast<std::uint32_t>(m.positions.size());
  const auto k = static_cast<std::size_t>(m.influences);
  const glm::vec3 centre = 0.5f * (lo + hi);
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 p((i & 1) != 0 ? hi.x : lo.x, (i & 2) != 0 ? hi.y : lo.y,
                      (i & 4) != 0 ? hi.z : lo.z);
    m.positions.push_back(p);
    m.normals.push_back(glm::normalize(p - centre));
    for (std::size_t s = 0; s < k; ++s) {
      m.joints.push_back(static_cast<std::uint16_t>(joint));
      m.weights.push_back(s == 0 ? 1.0f : 0.0f);
    }
  }
  // Faces as corner quads, counter-clockwise seen from outside.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    const auto at = [&](int i) { return first + static_cast<std::uint32_t>(q[i]); };
    m.indices.insert(m.indices.end(), {at(0), at(1), at(2), at(0), at(2), at(3)});
  }
  return first;
}

struct InnerAvatar {
  AvatarModel avatar;
  std::uint32_t outer_count = 0;  // the default avatar's vertices (the inner ones follow)
  std::uint32_t starts[3] = {};   // first vertex of each added part
};

// The default avatar with two eyeballs and a tongue inside its head.
InnerAvatar innerAvatar() {
  InnerAvatar out;
  Result<AvatarModel> a = makeDefaultAvatar();
  EXPECT_TRUE(a.ok());
  out.avatar = std::move(*a);
  SkinMesh& m = out.avatar.skin;
  out.outer_count = static_cast<std::uint32_t>(m.positions.size());
  const int head = findHeadJoint(out.avatar.skeleton);
  EXPECT_GE(head, 0);
  // The head's skin: the vertices the head bone carries most.
  Bounds box{glm::vec3(INFINITY), glm::vec3(-INFINITY)};
  const auto k = static_cast<std::size_t>(m.influences);
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    float w = 0.0f;
    for (std::size_t s = 0; s < k; ++s) {
      if (m.joints[v * k + s] == head) w += m.weights[v * k + s];
    }
    if (w < 0.99f) continue;
    box.min = glm::min(box.min, m.positions[v]);
    box.max = glm::max(box.max, m.positions[v]);
  }
  const glm::vec3 c = 0.5f * (box.min + box.max);
  const glm::vec3 h = 0.5f * (box.max - box.min);
  out.starts[0] = addSphere(m, c + glm::vec3(-0.3f * h.x, 0.1f * h.y, 0.3f * h.z), 0.012f, head);
  out.starts[1] = addSphere(m, c + glm::vec3(0.3f * h.x, 0.1f * h.y, 0.3f * h.z), 0.012f, head);
  out.starts[2] = addBox(m, c + glm::vec3(-0.015f, -0.35f * h.y - 0.004f, 0.0f),
                         c + glm::vec3(0.015f, -0.35f * h.y + 0.004f, 0.4f * h.z), head);
  out.avatar.look = {};  // (its texture coordinates and submeshes cover the skin alone)
  EXPECT_TRUE(validateSkinMesh(m, out.avatar.skeleton.jointCount()).ok());
  return out;
}

TEST(InnerLayers, FindsExactlyTheAddedParts) {
  const InnerAvatar ia = innerAvatar();
  const SkinMesh& m = ia.avatar.skin;
  Result<InnerLayers> layers = findInnerLayers(m.positions, m.indices);
  ASSERT_TRUE(layers.ok()) << layers.error().message;
  EXPECT_EQ(layers->innerLayerCount(), 3);
  EXPECT_EQ(layers->inner_vertices, static_cast<int>(m.positions.size() - ia.outer_count));
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    ASSERT_EQ(layers->inner[v], v >= ia.outer_count ? 1 : 0) << "vertex " << v;
  }
  for (const MeshComponent& c : layers->components) {
    std::printf("component: %d vertices, %d triangles, inner %d (in %d, %.2f inside)\n", c.vertices,
                c.triangles, c.inner ? 1 : 0, c.container, c.inside_share);
    if (c.inner) {
      EXPECT_EQ(c.container, layers->outer);
      EXPECT_GE(c.inside_share, 0.99f);
    }
  }
}

TEST(InnerLayers, NoneOnThePlainDefaultAvatar) {
  Result<AvatarModel> a = makeDefaultAvatar();
  ASSERT_TRUE(a.ok());
  Result<InnerLayers> layers = findInnerLayers(a->skin.positions, a->skin.indices);
  ASSERT_TRUE(layers.ok()) << layers.error().message;
  std::printf("default avatar: %zu components, %d inner\n", layers->components.size(),
              layers->innerLayerCount());
  EXPECT_EQ(layers->innerLayerCount(), 0);
  EXPECT_EQ(layers->inner_vertices, 0);
}

TEST(InnerLayers, NoneOnMakehuman) {
  VISTEL_REQUIRE_SHARED(glb, "avatars/makehuman_game_engine.glb");
  Result<AvatarModel> a = importGltfAvatar(glb);
  ASSERT_TRUE(a.ok()) << a.error().message;
  Result<InnerLayers> layers = findInnerLayers(a->skin.positions, a->skin.indices);
  ASSERT_TRUE(layers.ok()) << layers.error().message;
  std::printf("makehuman: %zu vertices, %zu components, %d inner\n", a->skin.positions.size(),
              layers->components.size(), layers->innerLayerCount());
  for (const MeshComponent& c : layers->components) {
    std::printf("  component: %d vertices, %d triangles, inner %d\n", c.vertices, c.triangles,
                c.inner ? 1 : 0);
  }
  EXPECT_EQ(layers->innerLayerCount(), 0);
}

TEST(InnerLayers, BadInputIsAnError) {
  const std::vector<glm::vec3> pos = {glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f),
                                      glm::vec3(0.0f, 1.0f, 0.0f)};
  EXPECT_FALSE(findInnerLayers(pos, std::vector<std::uint32_t>{0, 1}).ok());
  EXPECT_FALSE(findInnerLayers(pos, std::vector<std::uint32_t>{0, 1, 3}).ok());
  std::vector<glm::vec3> bad = pos;
  bad[1].y = NAN;
  EXPECT_FALSE(findInnerLayers(bad, std::vector<std::uint32_t>{0, 1, 2}).ok());
  Calibration c;
  EXPECT_FALSE(carryInnerLayersRigidly(std::vector<std::uint8_t>{1}, c).ok());
}

// The avatar with inner parts and its model built from the default humanoid map, as
// test::realAvatar builds the plain one (built once per process).
struct BuiltInner {
  InnerAvatar ia;
  ImplicitModel model;
  BuildReport report;
};
const BuiltInner& builtInner() {
  static const BuiltInner built = [] {
    BuiltInner b;
    b.ia = innerAvatar();
    Result<std::vector<JointMap>> maps = loadJointMaps();
    EXPECT_TRUE(maps.ok());
    if (!maps) return b;
    Result<const JointMap*> map = selectJointMap(*maps, b.ia.avatar.skeleton);
    Result<PrimitiveMapSpec> spec = loadPrimitiveMap();
    EXPECT_TRUE(map.ok() && spec.ok());
    if (!map || !spec) return b;
    Result<ImplicitModel> model = buildImplicitModel(b.ia.avatar, *spec, *map, {}, &b.report);
    EXPECT_TRUE(model.ok()) << model.error().message;
    if (model) b.model = std::move(*model);
    return b;
  }();
  return built;
}

// The built model carries the added parts rigidly; a ball pressed into the face while the
// head nods dents the outer skin and leaves every inner vertex at its skinned position.
TEST(InnerLayers, CarriedRigidlyUnderABallInTheFace) {
  const BuiltInner& built = builtInner();
  const InnerAvatar& ia = built.ia;
  ASSERT_FALSE(built.model.primitives.items.empty());
  const ImplicitModel& model = built.model;
  const BuildReport& report = built.report;
  const std::size_t nv = ia.avatar.skin.positions.size();
  EXPECT_EQ(report.calibration.inner, static_cast<int>(nv - ia.outer_count));
  for (std::size_t v = 0; v < nv; ++v) {
    ASSERT_EQ(innerVertex(model.calibration, v), v >= ia.outer_count) << "vertex " << v;
  }
  // The flag survives the model's bytes.
  Result<ImplicitModel> back = decodeImplicitModel(
      encodeImplicitModel(model), ia.avatar.skeleton.jointCount(), static_cast<int>(nv));
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->calibration.rigid, model.calibration.rigid);

  test::Body body;
  body.name = "inner";
  body.skeleton = ia.avatar.skeleton;
  body.mesh = ia.avatar.skin;
  body.model = model;
  body.init();
  const Posture rest = body.posture;
  const int head = findHeadJoint(body.skeleton);
  // The ball's centre: `depth` inside the face's most forward head vertex.
  glm::vec3 front(0.0f, 0.0f, -INFINITY);
  for (std::uint32_t v = 0; v < ia.outer_count; ++v) {
    const std::int16_t p = body.model.calibration.prims[v][0];
    if (p >= 0 && body.model.primitives.items[static_cast<std::size_t>(p)].name == "head" &&
        body.mesh.positions[v].z > front.z) {
      front = body.mesh.positions[v];
    }
  }
  BallSpec ball_spec;
  ball_spec.radius = 0.11f;
  auto ball = test::ballBody(ball_spec, front);
  ball->deform = false;  // rigid
  test::Scene scene;
  scene.bodies = {&body, ball.get()};
  int frame = 0;
  for (const float depth : {0.01f, 0.02f, 0.03f, 0.04f}) {
    body.posture = rest;
    body.posture.rotations[static_cast<std::size_t>(head)] =
        rest.rotations[static_cast<std::size_t>(head)] *
        glm::angleAxis(0.04f * static_cast<float>(frame), glm::vec3(1.0f, 0.0f, 0.0f));
    ball->placement =
        glm::translate(glm::mat4(1.0f), front + glm::vec3(0.0f, 0.0f, ball_spec.radius - depth));
    scene.step(frame / 30.0);
    int inner_off = 0, inner_flagged = 0, outer_contact = 0;
    float dent = 0.0f;
    for (std::size_t v = 0; v < nv; ++v) {
      const DeformState& st = body.state;
      if (v >= ia.outer_count) {
        inner_off += st.positions[v] != body.rigid_pos[v] || st.normals[v] != body.rigid_nrm[v];
        inner_flagged += st.flags[v] != 0 || st.contact_body[v] != -1 || st.depth[v] != 0.0f;
      } else if ((st.flags[v] & kVertexContact) != 0) {
        ++outer_contact;
        dent = std::max(dent, glm::dot(body.rigid_pos[v] - st.positions[v], body.rigid_nrm[v]));
      }
    }
    double area = 0.0;
    for (const BodyContact& c : body.state.contacts) area += c.partner == 1 ? c.area : 0.0;
    std::printf(
        "ball %.3f m deep, head turned %.2f rad: %d outer contact vertices, dent %.4f m, area "
        "%.5f m^2; inner vertices off their skinned position %d, flagged %d\n",
        depth, 0.04 * frame, outer_contact, dent, area, inner_off, inner_flagged);
    EXPECT_EQ(inner_off, 0) << "at " << depth;
    EXPECT_EQ(inner_flagged, 0) << "at " << depth;
    EXPECT_GT(outer_contact, 0) << "at " << depth;
    EXPECT_GT(dent, 0.5f * depth) << "at " << depth;
    ++frame;
  }
}

// The builder fits no primitive to an inner layer: the avatar with eyes and a tongue gets the
// very primitives of the avatar without them (fitted to them, the head's primitive shrank
// inside the skin: r_in 7.07 cm against 7.70).
TEST(InnerLayers, FitNoPrimitive) {
  const test::RealAvatar* plain = test::realAvatar("default");
  ASSERT_NE(plain, nullptr);
  const ImplicitModel& without = plain->model;
  const ImplicitModel& with = builtInner().model;
  ASSERT_EQ(with.primitives.items.size(), without.primitives.items.size());
  ASSERT_FALSE(with.primitives.items.empty());
  for (std::size_t k = 0; k < with.primitives.items.size(); ++k) {
    const Primitive& a = with.primitives.items[k];
    const Primitive& b = without.primitives.items[k];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.r_in, b.r_in) << a.name;
    EXPECT_EQ(a.r_out, b.r_out) << a.name;
    EXPECT_EQ(a.shape.a, b.shape.a) << a.name;
    EXPECT_EQ(a.shape.b, b.shape.b) << a.name;
  }
}

}  // namespace
}  // namespace vistel
