#include "test_avatar.hpp"

#include <cmath>
#include <string>

#include <glm/gtc/constants.hpp>

namespace vistel::test {

namespace {

struct JointDef {
  const char* name;
  const char* parent;
  glm::vec3 position;  // rest, model space
};

constexpr JointDef kJoints[] = {
    {"hips", nullptr, {0.0f, 1.00f, 0.0f}},
    {"spine", "hips", {0.0f, 1.15f, 0.0f}},
    {"chest", "spine", {0.0f, 1.32f, 0.0f}},
    {"neck", "chest", {0.0f, 1.52f, 0.0f}},
    {"head", "neck", {0.0f, 1.62f, 0.0f}},
    {"l_upperarm", "chest", {0.20f, 1.48f, 0.0f}},
    {"l_forearm", "l_upperarm", {0.48f, 1.48f, 0.0f}},
    {"l_hand", "l_forearm", {0.73f, 1.48f, 0.0f}},
    {"r_upperarm", "chest", {-0.20f, 1.48f, 0.0f}},
    {"r_forearm", "r_upperarm", {-0.48f, 1.48f, 0.0f}},
    {"r_hand", "r_forearm", {-0.73f, 1.48f, 0.0f}},
    {"l_thigh", "hips", {0.10f, 0.95f, 0.0f}},
    {"l_shin", "l_thigh", {0.10f, 0.52f, 0.0f}},
    {"l_foot", "l_shin", {0.10f, 0.09f, 0.0f}},
    {"r_thigh", "hips", {-0.10f, 0.95f, 0.0f}},
    {"r_shin", "r_thigh", {-0.10f, 0.52f, 0.0f}},
    {"r_foot", "r_shin", {-0.10f, 0.09f, 0.0f}},
};

// Appends a capsule's vertices and triangles (outward, counter-clockwise).
void appendCapsule(SkinMesh& skin, const TestCapsule& capsule, int rings) {
  const glm::vec3 axis_vec = capsule.b - capsule.a;
  const float length = glm::length(axis_vec);
  const glm::vec3 w = length > 1e-6f ? axis_vec / length : glm::vec3(0, 1, 0);
  const glm::vec3 helper = std::abs(w.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 u = glm::normalize(glm::cross(helper, w));
  const glm::vec3 v = glm::cross(w, u);
  const int around = 2 * rings;
  const auto base = static_cast<std::uint32_t>(skin.positions.size());
  // Latitude rings from the bottom pole (around a) to the top pole (around b).
  const int lat_count = 2 * rings + 2;
  for (int i = 0; i < lat_count; ++i) {
    const bool upper = i > rings;
    const int k = upper ? i - 1 : i;  // 0..2*rings
    const float phi = -glm::half_pi<float>() +
                      glm::pi<float>() * static_cast<float>(k) / static_cast<float>(2 * rings);
    const glm::vec3 center = upper ? capsule.b : capsule.a;
    for (int j = 0; j < around; ++j) {
      const float theta = glm::two_pi<float>() * static_cast<float>(j) / static_cast<float>(around);
      const glm::vec3 radial = u * std::cos(theta) + v * std::sin(theta);
      const glm::vec3 n = radial * std::cos(phi) + w * std::sin(phi);
      skin.positions.push_back(center + capsule.radius * n);
      skin.normals.push_back(glm::normalize(n));
      skin.joints.push_back(static_cast<std::uint16_t>(capsule.joint));
      skin.joints.push_back(0);
      skin.weights.push_back(1.0f);
      skin.weights.push_back(0.0f);
    }
  }
  for (int i = 0; i + 1 < lat_count; ++i) {
    for (int j = 0; j < around; ++j) {
      const auto p = [&](int ii, int jj) {
        return base + static_cast<std::uint32_t>(ii * around + (jj % around));
      };
      const std::uint32_t quad[6] = {p(i, j), p(i, j + 1),     p(i + 1, j + 1),
                                     p(i, j), p(i + 1, j + 1), p(i + 1, j)};
      skin.indices.insert(skin.indices.end(), quad, quad + 6);
    }
  }
}

}  // namespace

TestAvatar makeTestAvatar(int rings) {
  TestAvatar out;
  auto model = std::make_shared<AvatarModel>();
  model->name = "capsule_person";
  Skeleton& skeleton = model->skeleton;
  for (const JointDef& def : kJoints) {
    skeleton.names.emplace_back(def.name);
    const int parent = def.parent ? skeleton.find(def.parent) : kNoParent;
    skeleton.parents.push_back(parent);
    Transform local;
    local.translation = parent >= 0
                            ? def.position - kJoints[static_cast<std::size_t>(parent)].position
                            : def.position;
    skeleton.rest_local.push_back(local);
  }
  computeInverseBind(skeleton);

  const auto j = [&](const char* name) { return skeleton.find(name); };
  out.capsules = {
      {j("spine"), {0.0f, 0.92f, 0.0f}, {0.0f, 1.30f, 0.0f}, 0.14f},
      {j("chest"), {0.0f, 1.30f, 0.0f}, {0.0f, 1.44f, 0.0f}, 0.16f},
      {j("neck"), {0.0f, 1.50f, 0.0f}, {0.0f, 1.62f, 0.0f}, 0.05f},
      {j("head"), {0.0f, 1.72f, 0.01f}, {0.0f, 1.77f, 0.01f}, 0.10f},
      {j("l_upperarm"), {0.22f, 1.48f, 0.0f}, {0.46f, 1.48f, 0.0f}, 0.05f},
      {j("l_forearm"), {0.50f, 1.48f, 0.0f}, {0.71f, 1.48f, 0.0f}, 0.04f},
      {j("l_hand"), {0.75f, 1.48f, 0.0f}, {0.84f, 1.48f, 0.0f}, 0.035f},
      {j("r_upperarm"), {-0.22f, 1.48f, 0.0f}, {-0.46f, 1.48f, 0.0f}, 0.05f},
      {j("r_forearm"), {-0.50f, 1.48f, 0.0f}, {-0.71f, 1.48f, 0.0f}, 0.04f},
      {j("r_hand"), {-0.75f, 1.48f, 0.0f}, {-0.84f, 1.48f, 0.0f}, 0.035f},
      {j("l_thigh"), {0.10f, 0.92f, 0.0f}, {0.10f, 0.55f, 0.0f}, 0.07f},
      {j("l_shin"), {0.10f, 0.50f, 0.0f}, {0.10f, 0.12f, 0.0f}, 0.055f},
      {j("l_foot"), {0.10f, 0.05f, -0.02f}, {0.10f, 0.05f, 0.14f}, 0.04f},
      {j("r_thigh"), {-0.10f, 0.92f, 0.0f}, {-0.10f, 0.55f, 0.0f}, 0.07f},
      {j("r_shin"), {-0.10f, 0.50f, 0.0f}, {-0.10f, 0.12f, 0.0f}, 0.055f},
      {j("r_foot"), {-0.10f, 0.05f, -0.02f}, {-0.10f, 0.05f, 0.14f}, 0.04f},
  };
  model->skin.influences = 2;
  for (const TestCapsule& capsule : out.capsules) appendCapsule(model->skin, capsule, rings);
  out.model = model;
  return out;
}

Posture makeTestPosture(const AvatarModel& avatar) {
  const Skeleton& skeleton = avatar.skeleton;
  Posture posture = restPosture(skeleton);
  const auto set = [&](const char* name, float degrees, const glm::vec3& axis) {
    posture.rotations[static_cast<std::size_t>(skeleton.find(name))] =
        glm::angleAxis(glm::radians(degrees), axis);
  };
  // Arms down (left is +X: about -Z lowers it), elbows bent forward, head turned left.
  set("l_upperarm", -70.0f, {0, 0, 1});
  set("r_upperarm", 70.0f, {0, 0, 1});
  set("l_forearm", -40.0f, {0, 1, 0});
  set("r_forearm", 40.0f, {0, 1, 0});
  set("head", 20.0f, {0, 1, 0});
  set("l_thigh", -10.0f, {1, 0, 0});
  return posture;
}

}  // namespace vistel::test
