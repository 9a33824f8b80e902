#include "common/anim/ffd_skinning.hpp"

#include <algorithm>
#include <cassert>
#include <cctype>
#include <cmath>
#include <limits>
#include <string_view>

#include <fmt/format.h>

#include "common/anim/posture.hpp"
#include "common/anim/skinning.hpp"

namespace vistel {
namespace {

constexpr int kSamplesPerSegment = 32;  // rest-curve samples for the closest-point search
constexpr int kRefineSteps = 24;        // golden-section steps refining it

// Uniform cubic B-spline basis at t in [0,1] for the four control values i-1..i+2.
std::array<float, 4> bspline(float t) {
  const float s = 1.0f - t;
  const float t2 = t * t;
  const float t3 = t2 * t;
  return {s * s * s / 6.0f, (3.0f * t3 - 6.0f * t2 + 4.0f) / 6.0f,
          (-3.0f * t3 + 3.0f * t2 + 3.0f * t + 1.0f) / 6.0f, t3 / 6.0f};
}

// Uniform Catmull-Rom basis at t in [0,1] for the four control points i-1..i+2 (the curve
// passes through P_i at t = 0 and P_i+1 at t = 1).
std::array<float, 4> catmullRom(float t) {
  const float t2 = t * t;
  const float t3 = t2 * t;
  return {0.5f * (-t3 + 2.0f * t2 - t), 0.5f * (3.0f * t3 - 5.0f * t2 + 2.0f),
          0.5f * (-3.0f * t3 + 4.0f * t2 + t), 0.5f * (t3 - t2)};
}

// Keeps the non-zero entries of acc[0..count) (at most four) as index/weight slots.
void packSlots(const float* acc, int count, std::array<std::uint8_t, 4>& index,
               std::array<float, 4>& weight) {
  index.fill(0);
  weight.fill(0.0f);
  int slot = 0;
  for (int j = 0; j < count && slot < 4; ++j) {
    if (acc[j] == 0.0f) continue;
    index[static_cast<std::size_t>(slot)] = static_cast<std::uint8_t>(j);
    weight[static_cast<std::size_t>(slot)] = acc[j];
    ++slot;
  }
}

// Weights of the n + 1 control points at u in [0, n]: the Catmull-Rom spline through them,
// the end points reflected (P_-1 = 2 P_0 - P_1, P_n+1 = 2 P_n - P_n-1). An interpolating
// curve keeps the posed spine about as long as the chain (a B-spline cuts the corners of a
// bent chain and shrinks the torso: 1.7% of a bent tube's volume against 0.3%).
void pointWeights(float u, int n, std::array<std::uint8_t, 4>& index,
                  std::array<float, 4>& weight) {
  u = std::clamp(u, 0.0f, static_cast<float>(n));
  const int i = std::min(static_cast<int>(std::floor(u)), n - 1);
  const std::array<float, 4> b = catmullRom(u - static_cast<float>(i));
  float acc[kMaxSpineJoints + 1] = {};
  for (int s = 0; s < 4; ++s) {
    const int j = i - 1 + s;
    const float w = b[static_cast<std::size_t>(s)];
    if (j < 0) {
      acc[0] += 2.0f * w;
      acc[1] -= w;
    } else if (j > n) {
      acc[n] += 2.0f * w;
      acc[n - 1] -= w;
    } else {
      acc[j] += w;
    }
  }
  packSlots(acc, n + 1, index, weight);
}

// Weights of the n control frames at u in [0, n]: frame f sits at u = f + 1/2 (the middle
// of joint f's bone); beyond the ends the end frames repeat.
void frameWeights(float u, int n, std::array<std::uint8_t, 4>& index,
                  std::array<float, 4>& weight) {
  const float uf = std::clamp(u, 0.0f, static_cast<float>(n)) - 0.5f;
  const int i = static_cast<int>(std::floor(uf));
  const std::array<float, 4> b = bspline(uf - static_cast<float>(i));
  float acc[kMaxSpineJoints] = {};
  for (int s = 0; s < 4; ++s)
    acc[std::clamp(i - 1 + s, 0, n - 1)] += b[static_cast<std::size_t>(s)];
  packSlots(acc, n, index, weight);
}

glm::vec3 curveAt(std::span<const glm::vec3> points, float u) {
  const int n = static_cast<int>(points.size()) - 1;
  std::array<std::uint8_t, 4> index;
  std::array<float, 4> weight;
  pointWeights(u, n, index, weight);
  glm::vec3 c(0.0f);
  for (std::size_t s = 0; s < 4; ++s) c += weight[s] * points[index[s]];
  return c;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

int depth(const Skeleton& skeleton, int j) {
  int d = 0;
  for (; skeleton.parents[static_cast<std::size_t>(j)] != kNoParent; ++d) {
    j = skeleton.parents[static_cast<std::size_t>(j)];
  }
  return d;
}

// "head" in any case, else the shallowest joint whose name contains "head"; -1 if none.
int findHead(const Skeleton& skeleton) {
  int best = -1;
  for (int j = 0; j < skeleton.jointCount(); ++j) {
    const std::string name = lower(skeleton.names[static_cast<std::size_t>(j)]);
    if (name == "head") return j;
    if (name.find("head") != std::string::npos &&
        (best < 0 || depth(skeleton, j) < depth(skeleton, best))) {
      best = j;
    }
  }
  return best;
}

// The parameter of the rest curve's point closest to p: the nearest sample, refined by a
// golden-section search between its neighbours.
float closestParameter(std::span<const glm::vec3> points, std::span<const glm::vec3> samples,
                       const glm::vec3& p) {
  const int n = static_cast<int>(points.size()) - 1;
  const float step = 1.0f / static_cast<float>(kSamplesPerSegment);
  std::size_t nearest = 0;
  float best = std::numeric_limits<float>::max();
  for (std::size_t s = 0; s < samples.size(); ++s) {
    const glm::vec3 d = samples[s] - p;
    const float d2 = glm::dot(d, d);
    if (d2 < best) {
      best = d2;
      nearest = s;
    }
  }
  const float centre = static_cast<float>(nearest) * step;
  float a = std::max(centre - step, 0.0f);
  float b = std::min(centre + step, static_cast<float>(n));
  const float ratio = 0.5f * (std::sqrt(5.0f) - 1.0f);
  const auto dist2 = [&](float u) {
    const glm::vec3 d = curveAt(points, u) - p;
    return glm::dot(d, d);
  };
  for (int it = 0; it < kRefineSteps; ++it) {
    const float c = b - ratio * (b - a);
    const float d = a + ratio * (b - a);
    if (dist2(c) < dist2(d)) {
      b = d;
    } else {
      a = c;
    }
  }
  return 0.5f * (a + b);
}

}  // namespace

SpineLattice buildSpineLattice(const Skeleton& skeleton, const SkinMesh& mesh, int head_joint) {
  SpineLattice lattice;
  const int njoint = skeleton.jointCount();
  const auto nvert = static_cast<std::size_t>(mesh.vertexCount());
  const auto k = static_cast<std::size_t>(mesh.influences);

  // The head, and the weighted chain of its ancestors down to its parent.
  if (head_joint < 0 || head_joint >= njoint) head_joint = findHead(skeleton);
  if (head_joint < 0) {
    lattice.warning = "no spine: the skeleton has no head joint (no joint named like 'head')";
    return lattice;
  }
  std::vector<double> joint_weight(static_cast<std::size_t>(njoint), 0.0);
  for (std::size_t v = 0; v < nvert; ++v) {
    for (std::size_t s = 0; s < k; ++s)
      joint_weight[mesh.joints[v * k + s]] += mesh.weights[v * k + s];
  }
  std::vector<int> ancestors;  // head's parent up to the root
  for (int j = skeleton.parents[static_cast<std::size_t>(head_joint)]; j != kNoParent;
       j = skeleton.parents[static_cast<std::size_t>(j)]) {
    ancestors.push_back(j);
  }
  while (!ancestors.empty() && joint_weight[static_cast<std::size_t>(ancestors.back())] <= 0.0) {
    ancestors.pop_back();  // unweighted joints above the pelvis (a floor-level root)
  }
  const std::string& head_name = skeleton.names[static_cast<std::size_t>(head_joint)];
  if (ancestors.size() < 2) {
    lattice.warning =
        fmt::format("no spine: the head '{}' has {} skinned ancestor joint(s), the lattice needs 2",
                    head_name, ancestors.size());
    return lattice;
  }
  if (ancestors.size() > static_cast<std::size_t>(kMaxSpineJoints)) {
    lattice.warning =
        fmt::format("no spine: the chain below the head '{}' has {} joints (at most {})", head_name,
                    ancestors.size(), kMaxSpineJoints);
    return lattice;
  }
  lattice.chain.assign(ancestors.rbegin(), ancestors.rend());
  lattice.end_joint = head_joint;
  const int n = static_cast<int>(lattice.chain.size());

  // Control points at rest: the chain's joint origins, then the head's.
  const std::vector<glm::mat4> rest = restModelTransforms(skeleton);
  for (int j : lattice.chain)
    lattice.rest_points.emplace_back(rest[static_cast<std::size_t>(j)][3]);
  lattice.rest_points.emplace_back(rest[static_cast<std::size_t>(head_joint)][3]);
  lattice.in_chain.assign(static_cast<std::size_t>(njoint), 0);
  for (int j : lattice.chain) lattice.in_chain[static_cast<std::size_t>(j)] = 1;

  // Rest-curve samples for the closest-point search.
  std::vector<glm::vec3> samples(static_cast<std::size_t>(n * kSamplesPerSegment + 1));
  for (std::size_t s = 0; s < samples.size(); ++s) {
    samples[s] = curveAt(lattice.rest_points,
                         static_cast<float>(s) / static_cast<float>(kSamplesPerSegment));
  }

  // Per vertex: torso weight and lattice coordinates.
  lattice.torso.assign(nvert, 0.0f);
  lattice.coords.assign(nvert, SpineCoord{});
  for (std::size_t v = 0; v < nvert; ++v) {
    float torso = 0.0f;
    bool other = false;
    for (std::size_t s = 0; s < k; ++s) {
      const float w = mesh.weights[v * k + s];
      if (w <= 0.0f) continue;
      if (lattice.in_chain[mesh.joints[v * k + s]] != 0) {
        torso += w;
      } else {
        other = true;
      }
    }
    if (torso <= 0.0f) continue;
    lattice.torso[v] = other ? torso : 1.0f;  // 1 exactly: the sweep alone
    ++lattice.torso_vertices;
    SpineCoord& c = lattice.coords[v];
    const float u = closestParameter(lattice.rest_points, samples, mesh.positions[v]);
    pointWeights(u, n, c.point, c.point_w);
    frameWeights(u, n, c.frame, c.frame_w);
    c.anchor = curveAt(lattice.rest_points, u);
  }
  if (lattice.torso_vertices == 0) {
    lattice.warning =
        fmt::format("no spine: no skin weight on the chain below the head '{}'", head_name);
    lattice.chain.clear();
  }
  return lattice;
}

void poseSpineLattice(const SpineLattice& lattice, std::span<const DualQuat> skin,
                      SpineLatticePose& out) {
  const int n = static_cast<int>(lattice.chain.size());
  out.points = n == 0 ? 0 : n + 1;
  for (int f = 0; f < n; ++f) {
    const DualQuat& q = skin[static_cast<std::size_t>(lattice.chain[static_cast<std::size_t>(f)])];
    const auto fi = static_cast<std::size_t>(f);
    out.point[fi] = q.transformPoint(lattice.rest_points[fi]);
    // One hemisphere along the chain, so that the per-vertex blend needs no sign tests.
    out.frame[fi] = f > 0 && glm::dot(q.real, out.frame[fi - 1]) < 0.0f ? -q.real : q.real;
  }
  if (n > 0) {
    const auto last = static_cast<std::size_t>(n);
    out.point[last] =
        skin[static_cast<std::size_t>(lattice.end_joint)].transformPoint(lattice.rest_points[last]);
  }
}

glm::vec3 spineCurvePoint(const SpineLatticePose& pose, float u) {
  if (pose.points < 2) return glm::vec3(0.0f);
  return curveAt(std::span(pose.point.data(), static_cast<std::size_t>(pose.points)), u);
}

void skinSpineLattice(const SkinMesh& mesh, const SpineLattice& lattice,
                      std::span<const DualQuat> skin, const SpineLatticePose& pose,
                      std::size_t first, std::span<glm::vec3> out_positions,
                      std::span<glm::vec3> out_normals) {
  assert(out_positions.size() == out_normals.size());
  assert(first + out_positions.size() <= mesh.positions.size());
  if (lattice.empty() || pose.points == 0) {
    skinDualQuaternion(mesh, skin, first, out_positions, out_normals);
    return;
  }
  const auto k = static_cast<std::size_t>(mesh.influences);
  const std::size_t count = out_positions.size();
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t v = first + i;
    const float torso = lattice.torso[v];
    if (torso <= 0.0f) {
      // Outside the torso (a run of such vertices): dual quaternions, skinDualQuaternion.
      std::size_t end = i + 1;
      while (end < count && lattice.torso[first + end] <= 0.0f) ++end;
      skinDualQuaternion(mesh, skin, v, out_positions.subspan(i, end - i),
                         out_normals.subspan(i, end - i));
      i = end - 1;
      continue;
    }
    // The sweep: the posed curve point and the blended frame rotation at the vertex's u.
    const SpineCoord& c = lattice.coords[v];
    glm::vec3 curve(0.0f);
    glm::quat rot(0.0f, 0.0f, 0.0f, 0.0f);
    for (std::size_t s = 0; s < 4; ++s) {
      curve += c.point_w[s] * pose.point[c.point[s]];
      rot = rot + pose.frame[c.frame[s]] * c.frame_w[s];
    }
    rot = rot * (1.0f / glm::length(rot));
    if (torso >= 1.0f) {
      out_positions[i] = curve + rot * (mesh.positions[v] - c.anchor);
      out_normals[i] = rot * mesh.normals[v];
      continue;
    }
    // Partly torso: the sweep's rigid transform in the vertex's dual-quaternion blend.
    DualQuat acc = DualQuat::fromRigid(rot, curve - rot * c.anchor);
    acc.real = acc.real * torso;
    acc.dual = acc.dual * torso;
    for (std::size_t s = 0; s < k; ++s) {
      const float w = mesh.weights[v * k + s];
      const std::uint16_t j = mesh.joints[v * k + s];
      if (w > 0.0f && lattice.in_chain[j] == 0) accumulate(acc, skin[j], w, rot);
    }
    const DualQuat q = normalized(acc);
    out_positions[i] = q.transformPoint(mesh.positions[v]);
    out_normals[i] = q.transformVector(mesh.normals[v]);
  }
}

}  // namespace vistel
