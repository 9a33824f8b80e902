#include "common/anim/skinning.hpp"

#include <cassert>

namespace vistel {

void skinLinear(const SkinMesh& mesh, std::span<const glm::mat4> skin, std::size_t first,
                std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals) {
  assert(out_positions.size() == out_normals.size());
  assert(first + out_positions.size() <= mesh.positions.size());
  const auto k = static_cast<std::size_t>(mesh.influences);
  for (std::size_t i = 0; i < out_positions.size(); ++i) {
    const std::size_t v = first + i;
    // Blend the influencing matrices.
    glm::mat4 m(0.0f);
    for (std::size_t s = 0; s < k; ++s) {
      const float w = mesh.weights[v * k + s];
      if (w > 0.0f) m += skin[mesh.joints[v * k + s]] * w;
    }
    // Transform the rest point, and the normal by the cofactor matrix of the blend (the
    // inverse transpose up to a positive factor for orientation-preserving blends).
    out_positions[i] = glm::vec3(m * glm::vec4(mesh.positions[v], 1.0f));
    const glm::vec3 c0(m[0]), c1(m[1]), c2(m[2]);
    const glm::mat3 cofactor(glm::cross(c1, c2), glm::cross(c2, c0), glm::cross(c0, c1));
    const glm::vec3 n = cofactor * mesh.normals[v];
    const float len = glm::length(n);
    out_normals[i] = len > 0.0f ? n / len : mesh.normals[v];
  }
}

void skinDualQuaternion(const SkinMesh& mesh, std::span<const DualQuat> skin, std::size_t first,
                        std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals) {
  assert(out_positions.size() == out_normals.size());
  assert(first + out_positions.size() <= mesh.positions.size());
  const auto k = static_cast<std::size_t>(mesh.influences);
  for (std::size_t i = 0; i < out_positions.size(); ++i) {
    const std::size_t v = first + i;
    // Blend in the hemisphere of the first influence, then renormalise.
    const glm::quat pivot = skin[mesh.joints[v * k]].real;
    DualQuat acc;
    acc.real = glm::quat(0.0f, 0.0f, 0.0f, 0.0f);
    for (std::size_t s = 0; s < k; ++s) {
      const float w = mesh.weights[v * k + s];
      if (w > 0.0f) accumulate(acc, skin[mesh.joints[v * k + s]], w, pivot);
    }
    const DualQuat q = normalized(acc);
    out_positions[i] = q.transformPoint(mesh.positions[v]);
    out_normals[i] = q.transformVector(mesh.normals[v]);
  }
}

std::string_view skinningMethodName(SkinningMethod method) {
  switch (method) {
    case SkinningMethod::kLinear:
      return "lbs";
    case SkinningMethod::kDualQuaternion:
      return "dqs";
    case SkinningMethod::kSpineFfd:
      return "ffd";
    case SkinningMethod::kRigidSlerp:
      return "slerp";
  }
  return "dqs";
}

std::optional<SkinningMethod> parseSkinningMethod(std::string_view name) {
  for (SkinningMethod m : {SkinningMethod::kLinear, SkinningMethod::kDualQuaternion,
                           SkinningMethod::kSpineFfd, SkinningMethod::kRigidSlerp}) {
    if (skinningMethodName(m) == name) return m;
  }
  return std::nullopt;
}

void toDualQuats(std::span<const glm::mat4> skin, std::span<DualQuat> out) {
  assert(out.size() == skin.size());
  for (std::size_t j = 0; j < skin.size(); ++j) out[j] = DualQuat::fromMatrix(skin[j]);
}

void skinMesh(const SkinMesh& mesh, SkinningMethod method, std::span<const glm::mat4> skin,
              std::span<DualQuat> scratch_dq, std::span<glm::vec3> out_positions,
              std::span<glm::vec3> out_normals) {
  if (method == SkinningMethod::kLinear) {
    skinLinear(mesh, skin, 0, out_positions, out_normals);
    return;
  }
  toDualQuats(skin, scratch_dq);
  skinDualQuaternion(mesh, scratch_dq, 0, out_positions, out_normals);
}

}  // namespace vistel
