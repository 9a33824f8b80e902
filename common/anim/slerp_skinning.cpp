#include "common/anim/slerp_skinning.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"

namespace vistel {
namespace {

// The share t of rotation q: the slerp from the identity along the shorter arc (linear,
// renormalised, when q is nearly the identity).
glm::quat share(glm::quat q, float t) {
  if (q.w < 0.0f) q = -q;
  if (q.w > 0.9995f) {
    return glm::normalize(glm::quat(1.0f + (q.w - 1.0f) * t, q.x * t, q.y * t, q.z * t));
  }
  const float theta = std::acos(q.w);
  const float inv_sin = 1.0f / std::sin(theta);
  const float a = std::sin((1.0f - t) * theta) * inv_sin;
  const float b = std::sin(t * theta) * inv_sin;
  return glm::quat(a + b * q.w, b * q.x, b * q.y, b * q.z);
}

// Appends the steps from bone a to bone i (a != i) in the order they apply: i's side of
// the path below the lowest common ancestor (i's own joint first), then a's side, climbing
// (inverse shares) from the top down to a's own joint.
void appendPath(const SlerpRig& rig, const std::vector<int>& depth, int a, int i,
                std::vector<std::int32_t>& out) {
  int x = a, y = i;
  std::vector<int> up, down;  // a's side (a first), i's side (i first)
  while (depth[static_cast<std::size_t>(x)] > depth[static_cast<std::size_t>(y)]) {
    up.push_back(x);
    x = rig.parent[static_cast<std::size_t>(x)];
  }
  while (depth[static_cast<std::size_t>(y)] > depth[static_cast<std::size_t>(x)]) {
    down.push_back(y);
    y = rig.parent[static_cast<std::size_t>(y)];
  }
  while (x != y) {
    up.push_back(x);
    down.push_back(y);
    x = rig.parent[static_cast<std::size_t>(x)];
    y = rig.parent[static_cast<std::size_t>(y)];
  }
  // T_a^-1 T_i = E_up0^-1 ... E_upN^-1 E_downN ... E_down0 acting on the point: the
  // rightmost (i's own joint) first.
  for (int j : down) out.push_back(j);
  for (auto it = up.rbegin(); it != up.rend(); ++it) out.push_back(~*it);
}

}  // namespace

SlerpRig buildSlerpRig(const Skeleton& skeleton, const SkinMesh& mesh) {
  SlerpRig rig;
  const auto njoint = static_cast<std::size_t>(skeleton.jointCount());
  const auto nvert = static_cast<std::size_t>(mesh.vertexCount());
  const auto k = static_cast<std::size_t>(mesh.influences);
  const std::vector<glm::mat4> rest = restModelTransforms(skeleton);
  rig.parent = skeleton.parents;
  rig.origin.resize(njoint);
  std::vector<int> depth(njoint, 0);
  for (std::size_t j = 0; j < njoint; ++j) {
    rig.origin[j] = glm::vec3(rest[j][3]);
    if (j > 0) depth[j] = depth[static_cast<std::size_t>(rig.parent[j])] + 1;  // parents precede
  }
  rig.dominant.assign(nvert, 0);
  rig.path_begin.assign(nvert * k + 1, 0);
  for (std::size_t v = 0; v < nvert; ++v) {
    std::size_t a = 0;
    for (std::size_t s = 1; s < k; ++s) {
      if (mesh.weights[v * k + s] > mesh.weights[v * k + a]) a = s;
    }
    rig.dominant[v] = static_cast<std::uint8_t>(a);
    for (std::size_t s = 0; s < k; ++s) {
      rig.path_begin[v * k + s] = static_cast<std::uint32_t>(rig.path.size());
      const int ja = mesh.joints[v * k + a];
      const int js = mesh.joints[v * k + s];
      if (s != a && mesh.weights[v * k + s] > 0.0f && js != ja) {
        appendPath(rig, depth, ja, js, rig.path);
      }
    }
  }
  rig.path_begin[nvert * k] = static_cast<std::uint32_t>(rig.path.size());
  return rig;
}

void poseSlerpRig(const SlerpRig& rig, std::span<const DualQuat> skin, std::span<SlerpJoint> out) {
  assert(out.size() == rig.parent.size() && skin.size() == rig.parent.size());
  for (std::size_t j = 1; j < out.size(); ++j) {
    // Joint j relative to its parent, in bind space: L about o_j, then tau.
    const DualQuat& qj = skin[j];
    const DualQuat& qp = skin[static_cast<std::size_t>(rig.parent[j])];
    const glm::quat parent_inv = glm::conjugate(qp.real);
    const glm::vec3& o = rig.origin[j];
    out[j].local = parent_inv * qj.real;
    out[j].tau = parent_inv * (qj.transformPoint(o) - qp.transformPoint(o));
  }
}

void skinRigidSlerp(const SkinMesh& mesh, const SlerpRig& rig, std::span<const DualQuat> skin,
                    std::span<const SlerpJoint> joints, std::size_t first,
                    std::span<glm::vec3> out_positions, std::span<glm::vec3> out_normals) {
  assert(out_positions.size() == out_normals.size());
  assert(first + out_positions.size() <= mesh.positions.size());
  const auto k = static_cast<std::size_t>(mesh.influences);
  assert(rig.path_begin.size() == mesh.positions.size() * k + 1);
  for (std::size_t i = 0; i < out_positions.size(); ++i) {
    const std::size_t v = first + i;
    float total = 0.0f;
    for (std::size_t s = 0; s < k; ++s) total += std::max(mesh.weights[v * k + s], 0.0f);
    // In the dominant bone's bind frame: each other bone's share of every joint between.
    glm::vec3 p = mesh.positions[v];
    glm::quat turn(1.0f, 0.0f, 0.0f, 0.0f);
    for (std::size_t s = 0; s < k; ++s) {
      const float w = mesh.weights[v * k + s] / total;
      if (w <= 0.0f) continue;
      for (std::uint32_t e = rig.path_begin[v * k + s]; e < rig.path_begin[v * k + s + 1]; ++e) {
        const std::int32_t step = rig.path[e];
        const auto j = static_cast<std::size_t>(step >= 0 ? step : ~step);
        const glm::vec3& o = rig.origin[j];
        const SlerpJoint& joint = joints[j];
        if (step >= 0) {
          const glm::quat r = share(joint.local, w);
          p = o + r * (p - o) + w * joint.tau;
          turn = r * turn;
        } else {
          const glm::quat r = share(glm::conjugate(joint.local), w);
          p = o + r * (p - o - w * joint.tau);
          turn = r * turn;
        }
      }
    }
    // Then rigidly with the dominant bone.
    const DualQuat& qa = skin[mesh.joints[v * k + rig.dominant[v]]];
    out_positions[i] = qa.transformPoint(p);
    out_normals[i] = glm::normalize(qa.real * turn) * mesh.normals[v];
  }
}

}  // namespace vistel
