#include "tests/deform/fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/deform/posed_primitives.hpp"
#include "common/deform/vertex_field.hpp"
#include "offline/gltf/gltf_import.hpp"
#include "offline/synth/default_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel::test {

std::string armMapToml(std::string_view material) {
  return fmt::format(R"(
iso = 0.5
[material]
{}
[[primitive]]
name = "upper"
shape = "cone_sphere"
bone = "upper"
from = "upper"
to = "fore"
[[primitive]]
name = "fore"
shape = "cone_sphere"
bone = "fore"
from = "fore"
to = "tip"
[[primitive]]
name = "elbow"
role = "joint"
shape = "sphere"
bone = "fore"
at = "fore"
between = ["upper", "fore"]
[[primitive]]
name = "elbow_bone"
role = "bone"
shape = "sphere"
bone = "fore"
at = "fore"
blend = "elbow"
offset = [0.0, -1.0, 0.0]
depth = 0.6
)",
                     material);
}

AvatarModel makeArmAvatar(float length, float radius, float blend, int rings, int sides) {
  AvatarModel a;
  a.name = "arm";
  Skeleton& s = a.skeleton;
  s.names = {"upper", "fore", "tip"};
  s.parents = {kNoParent, 0, 1};
  s.rest_local.resize(3);
  s.rest_local[1].translation = glm::vec3(length, 0.0f, 0.0f);
  s.rest_local[2].translation = glm::vec3(length, 0.0f, 0.0f);
  computeInverseBind(s);
  SkinMesh& m = a.skin;
  m.influences = 2;
  const auto add_vertex = [&](glm::vec3 p, glm::vec3 n) {
    m.positions.push_back(p);
    m.normals.push_back(n);
    const float t = std::clamp((p.x - (length - blend)) / (2.0f * blend), 0.0f, 1.0f);
    m.joints.insert(m.joints.end(), {0, 1});
    m.weights.insert(m.weights.end(), {1.0f - t, t});
  };
  for (int i = 0; i <= rings; ++i) {
    const float x = 2.0f * length * static_cast<float>(i) / static_cast<float>(rings);
    for (int k = 0; k < sides; ++k) {
      const float ang =
          2.0f * std::numbers::pi_v<float> * static_cast<float>(k) / static_cast<float>(sides);
      const glm::vec3 n(0.0f, std::cos(ang), std::sin(ang));
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
  const auto c0 = static_cast<std::uint32_t>(m.positions.size());
  add_vertex(glm::vec3(0.0f), glm::vec3(-1, 0, 0));
  const auto c1 = static_cast<std::uint32_t>(m.positions.size());
  add_vertex(glm::vec3(2.0f * length, 0.0f, 0.0f), glm::vec3(1, 0, 0));
  for (int k = 0; k < sides; ++k) {
    m.indices.insert(m.indices.end(), {c0, ring(0, k + 1), ring(0, k)});
    m.indices.insert(m.indices.end(), {c1, ring(rings, k), ring(rings, k + 1)});
  }
  return a;
}

void Body::init() {
  const auto nj = static_cast<std::size_t>(skeleton.jointCount());
  model_xf.resize(nj);
  skin_xf.resize(nj);
  dq.resize(nj);
  rigid_pos.resize(mesh.positions.size());
  rigid_nrm.resize(mesh.positions.size());
  if (posture.rotations.empty()) posture = restPosture(skeleton);
  const Status st = initDeformState(model, mesh.indices, state);
  EXPECT_TRUE(st.ok()) << (st.ok() ? "" : st.error().message);
}

void Body::pose() {
  poseSkeleton(skeleton, posture, model_xf);
  skinningMatrices(skeleton, model_xf, skin_xf);
  for (glm::mat4& m : skin_xf) m = placement * m;
  skinMesh(mesh, SkinningMethod::kDualQuaternion, skin_xf, dq, rigid_pos, rigid_nrm);
  posePrimitives(model.primitives, skin_xf, posed);
}

DeformInput Body::input(double time) const {
  DeformInput in;
  in.rigid_positions = rigid_pos;
  in.rigid_normals = rigid_nrm;
  in.indices = mesh.indices;
  in.rest_positions = mesh.positions;
  in.time = time;
  return in;
}

std::unique_ptr<Body> armBody(std::string_view material) {
  auto b = std::make_unique<Body>();
  AvatarModel avatar = makeArmAvatar();
  b->name = "arm";
  b->skeleton = avatar.skeleton;
  b->mesh = avatar.skin;
  Result<PrimitiveMapSpec> spec = parsePrimitiveMap(armMapToml(material), "arm.toml");
  EXPECT_TRUE(spec.ok()) << (spec.ok() ? "" : spec.error().message);
  Result<ImplicitModel> model = buildImplicitModel(avatar, *spec, nullptr);
  EXPECT_TRUE(model.ok()) << (model.ok() ? "" : model.error().message);
  b->model = std::move(*model);
  b->init();
  return b;
}

std::unique_ptr<Body> ballBody(const BallSpec& spec, const glm::vec3& centre) {
  auto b = std::make_unique<Body>();
  Result<BallBody> ball = makeBall(spec);
  EXPECT_TRUE(ball.ok()) << (ball.ok() ? "" : ball.error().message);
  b->name = "ball";
  b->skeleton = ball->skeleton;
  b->mesh = ball->mesh;
  b->model = std::move(ball->model);
  b->placement = glm::translate(glm::mat4(1.0f), centre);
  b->init();
  return b;
}

const RealAvatar* realAvatar(const std::string& which) {
  static std::map<std::string, std::unique_ptr<RealAvatar>> cache;
  auto& slot = cache[which];
  if (slot) return slot.get();
  auto a = std::make_unique<RealAvatar>();
  // "<avatar>:free": built with its free vertices left free (BuildOptions).
  const bool keep_free = which.ends_with(":free");
  const std::string base = keep_free ? which.substr(0, which.size() - 5) : which;
  Result<AvatarModel> avatar =
      base == "makehuman" ? importGltfAvatar(sharedDataPath("avatars/makehuman_game_engine.glb"))
                          : makeDefaultAvatar();
  if (!avatar) {
    ADD_FAILURE() << which << ": " << avatar.error().message;
    return nullptr;
  }
  a->avatar = std::move(*avatar);
  Result<std::vector<JointMap>> maps = loadJointMaps();
  if (!maps) {
    ADD_FAILURE() << maps.error().message;
    return nullptr;
  }
  a->maps = std::move(*maps);
  Result<const JointMap*> map = selectJointMap(a->maps, a->avatar.skeleton);
  if (!map) {
    ADD_FAILURE() << map.error().message;
    return nullptr;
  }
  a->map = *map;
  Result<PrimitiveMapSpec> spec = loadPrimitiveMap();
  if (!spec) {
    ADD_FAILURE() << spec.error().message;
    return nullptr;
  }
  BuildOptions options;
  options.adopt_free_vertices = !keep_free;
  Result<ImplicitModel> model = buildImplicitModel(a->avatar, *spec, a->map, options, &a->report);
  if (!model) {
    ADD_FAILURE() << which << ": " << model.error().message;
    return nullptr;
  }
  a->model = std::move(*model);
  slot = std::move(a);
  return slot.get();
}

std::unique_ptr<Body> realBody(const RealAvatar& a) {
  auto b = std::make_unique<Body>();
  b->name = a.avatar.name;
  b->skeleton = a.avatar.skeleton;
  b->mesh = a.avatar.skin;
  b->model = a.model;
  b->init();
  return b;
}

void Scene::step(double time) {
  views.resize(bodies.size());
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    bodies[i]->pose();
    views[i] = BodyView{&bodies[i]->model.graph, &bodies[i]->posed, bodies[i]->velocity,
                        bodies[i]->restitution};
  }
  buildInteractions(views, scratch, list);
  states.assign(bodies.size(), nullptr);
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    Body& b = *bodies[i];
    if (!b.deform) continue;
    deformSkin(b.model, views, static_cast<int>(i), list, b.input(time), b.state, options, pool);
    states[i] = &b.state;
  }
  combineContacts(states, contacts);
}

void bendArm(Body& arm, float angle) {
  arm.posture.rotations[1] = glm::angleAxis(angle, glm::vec3(0.0f, 0.0f, 1.0f));
}

float maxDisplacement(const Body& b) {
  float m = 0.0f;
  for (std::size_t v = 0; v < b.rigid_pos.size(); ++v) {
    m = std::max(m, glm::length(b.state.positions[v] - b.rigid_pos[v]));
  }
  return m;
}

void expectRestsExactly(Body& b, const std::string& name) {
  PosedPrimitives rest;
  std::vector<glm::mat4> identity(static_cast<std::size_t>(b.skeleton.jointCount()),
                                  glm::mat4(1.0f));
  posePrimitives(b.model.primitives, identity, rest);
  for (int v = 0; v < b.mesh.vertexCount(); ++v) {
    const auto vi = static_cast<std::size_t>(v);
    if (b.model.calibration.vertex_class[vi] == VertexClass::kFree) continue;
    const float f =
        b.model.calibration.w[vi] * vertexDensity(b.model, rest, v, b.mesh.positions[vi]);
    ASSERT_NEAR(f, b.model.primitives.iso, 1e-5f) << name << " vertex " << v;
  }
  Scene scene;
  scene.bodies = {&b};
  scene.step(0.0);
  EXPECT_LT(maxDisplacement(b), 1e-5f) << name;
  EXPECT_EQ(b.state.counters.unsolved_vertices, 0) << name;
  EXPECT_EQ(b.state.counters.contact_vertices, 0) << name;
}

std::optional<BallTouch> rigidBallTouch(const Body& b, int v, float radius) {
  const float r = radius;
  const BodyView view{nullptr, &b.posed};
  BallStepOptions still;
  still.gravity = glm::vec3(0.0f);
  still.floor = false;
  const auto touches = [&](const glm::vec3& c) {
    BallState ball;
    ball.position = c;
    ball.radius = r;
    return stepBall(ball, {&view, 1}, 1e-6f, still).contact_count > 0;
  };
  const auto deepest = [&](const glm::vec3& c) {
    BallTouch out{-INFINITY, -1};
    for (std::size_t x = 0; x < b.rigid_pos.size(); ++x) {
      const float d = r - glm::length(b.rigid_pos[x] - c);
      if (d > out.depth) out = {d, static_cast<int>(x)};
    }
    return out;
  };
  const auto vi = static_cast<std::size_t>(v);
  const glm::vec3 n = glm::normalize(b.rigid_nrm[vi]);
  const glm::vec3 x0 = b.rigid_pos[vi];
  if (deepest(x0 + (r + 0.06f) * n).depth > 0.0f) return std::nullopt;
  float t = 0.06f;
  while (t > -0.06f && !touches(x0 + (r + t) * n)) t -= 0.001f;
  float apart = t + 0.001f;
  for (int i = 0; i < 7; ++i) {
    const float mid = 0.5f * (apart + t);
    (touches(x0 + (r + mid) * n) ? t : apart) = mid;
  }
  return deepest(x0 + (r + t) * n);
}

SoftBallShare softBallAt(const RealAvatar& avatar, int v) {
  constexpr float kRadius = 0.1f;
  auto body = realBody(avatar);
  body->pose();
  const auto vi = static_cast<std::size_t>(v);
  const glm::vec3 n = glm::normalize(body->rigid_nrm[vi]);
  BallSpec spec;
  spec.radius = kRadius;
  spec.stiffness = 3.0e4f;
  auto ball = ballBody(spec, body->rigid_pos[vi] + (kRadius - 0.02f) * n);
  Scene scene;
  scene.bodies = {body.get(), ball.get()};
  scene.step(0.0);
  const auto deepest = [](const Body& b, int partner) {
    float m = 0.0f;
    for (std::size_t x = 0; x < b.rigid_pos.size(); ++x) {
      if (b.state.contact_body[x] != partner) continue;
      m = std::max(m, glm::length(b.state.positions[x] - b.rigid_pos[x]));
    }
    return m;
  };
  SoftBallShare s;
  s.body_move = deepest(*body, 1);
  s.ball_move = deepest(*ball, 0);
  const std::int16_t p = body->model.calibration.prims[vi][0];
  const float k_body = body->model.primitives.items[static_cast<std::size_t>(p)].stiffness;
  s.expected = spec.stiffness / (spec.stiffness + k_body);
  for (const PairContact& c : scene.contacts) {
    if (c.body_a == 0 && c.body_b == 1) {
      s.area_body = c.area_a;
      s.area_ball = c.area_b;
    }
  }
  s.free_site = body->model.calibration.vertex_class[vi] == VertexClass::kFree;
  return s;
}

}  // namespace vistel::test
