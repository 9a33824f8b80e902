#include "tests/scene/scene_fixtures.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "offline/build/build_model.hpp"

namespace vistel::test {
namespace {

constexpr float kLength = 0.3f;
constexpr float kRadius = 0.04f;
constexpr float kBlend = 0.05f;
constexpr int kRings = 40;
constexpr int kSides = 20;

constexpr const char* kTubeMap = R"(
iso = 0.5
[material]
stiffness = 30000.0
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
)";

AvatarModel tubeMesh() {
  AvatarModel a;
  a.name = "tube";
  Skeleton& s = a.skeleton;
  s.names = {"upper", "fore", "tip"};
  s.parents = {kNoParent, 0, 1};
  s.rest_local.resize(3);
  s.rest_local[1].translation = glm::vec3(kLength, 0.0f, 0.0f);
  s.rest_local[2].translation = glm::vec3(kLength, 0.0f, 0.0f);
  computeInverseBind(s);
  SkinMesh& m = a.skin;
  m.influences = 2;
  // Rings of vertices along +X; weights move from "upper" to "fore" across the elbow.
  const auto vertex = [&](const glm::vec3& p, const glm::vec3& n) {
    m.positions.push_back(p);
    m.normals.push_back(n);
    const float t = std::clamp((p.x - (kLength - kBlend)) / (2.0f * kBlend), 0.0f, 1.0f);
    m.joints.insert(m.joints.end(), {0, 1});
    m.weights.insert(m.weights.end(), {1.0f - t, t});
  };
  for (int i = 0; i <= kRings; ++i) {
    const float x = 2.0f * kLength * static_cast<float>(i) / kRings;
    for (int k = 0; k < kSides; ++k) {
      const float angle = 2.0f * std::numbers::pi_v<float> * static_cast<float>(k) / kSides;
      const glm::vec3 n(0.0f, std::cos(angle), std::sin(angle));
      vertex(glm::vec3(x, 0.0f, 0.0f) + kRadius * n, n);
    }
  }
  const auto id = [](int i, int k) { return static_cast<std::uint32_t>(i * kSides + k % kSides); };
  for (int i = 0; i < kRings; ++i) {
    for (int k = 0; k < kSides; ++k) {
      m.indices.insert(m.indices.end(), {id(i, k), id(i, k + 1), id(i + 1, k + 1)});
      m.indices.insert(m.indices.end(), {id(i, k), id(i + 1, k + 1), id(i + 1, k)});
    }
  }
  // End caps: a centre vertex each.
  const auto c0 = static_cast<std::uint32_t>(m.positions.size());
  vertex(glm::vec3(0.0f), glm::vec3(-1.0f, 0.0f, 0.0f));
  const auto c1 = static_cast<std::uint32_t>(m.positions.size());
  vertex(glm::vec3(2.0f * kLength, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f));
  for (int k = 0; k < kSides; ++k) {
    m.indices.insert(m.indices.end(), {c0, id(0, k + 1), id(0, k)});
    m.indices.insert(m.indices.end(), {c1, id(kRings, k), id(kRings, k + 1)});
  }
  return a;
}

}  // namespace

std::shared_ptr<const AvatarModel> tubeAvatar() {
  static const std::shared_ptr<const AvatarModel> tube = [] {
    auto a = std::make_shared<AvatarModel>(tubeMesh());
    Result<PrimitiveMapSpec> spec = parsePrimitiveMap(kTubeMap, "tube.toml");
    EXPECT_TRUE(spec.ok()) << (spec.ok() ? "" : spec.error().message);
    Result<ImplicitModel> model = buildImplicitModel(*a, *spec, nullptr);
    EXPECT_TRUE(model.ok()) << (model.ok() ? "" : model.error().message);
    if (model.ok()) a->implicit = std::move(*model);
    return std::shared_ptr<const AvatarModel>(std::move(a));
  }();
  return tube;
}

std::shared_ptr<const AvatarModel> ballAvatar(float radius, float stiffness) {
  BallSpec spec;
  spec.radius = radius;
  spec.stiffness = stiffness;
  spec.subdivisions = 3;
  Result<std::shared_ptr<const AvatarModel>> ball = makeBallAvatar(spec);
  EXPECT_TRUE(ball.ok()) << (ball.ok() ? "" : ball.error().message);
  return ball.ok() ? *ball : nullptr;
}

void bendTube(Posture& posture, float angle) {
  posture.rotations[1] = glm::angleAxis(angle, glm::vec3(0.0f, 0.0f, 1.0f));
}

glm::mat4 at(const glm::vec3& position) { return glm::translate(glm::mat4(1.0f), position); }

}  // namespace vistel::test
