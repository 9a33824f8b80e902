#include "common/sensors/posture_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "common/sensors/rotation_utils.hpp"

namespace vistel {
namespace {

struct Posed {
  std::vector<glm::vec3> position;  // (nframe * njoint)
  std::vector<glm::quat> rotation;  // (nframe * njoint)
};

Posed pose(const Skeleton& skeleton, std::span<const Posture> postures) {
  const std::size_t n = static_cast<std::size_t>(skeleton.jointCount());
  Posed out;
  out.position.resize(postures.size() * n);
  out.rotation.resize(postures.size() * n);
  std::vector<glm::mat4> model(n);
  for (std::size_t f = 0; f < postures.size(); ++f) {
    poseSkeleton(skeleton, postures[f], model);
    for (std::size_t j = 0; j < n; ++j) {
      out.position[f * n + j] = glm::vec3(model[j][3]);
      out.rotation[f * n + j] = glm::normalize(glm::quat_cast(glm::mat3(model[j])));
    }
  }
  return out;
}

// Mean |third difference| / dt^3 over the joints (every joint when `joints` is empty).
double meanJerk(const std::vector<glm::vec3>& p, std::size_t frames, std::size_t n, double dt,
                std::span<const int> joints = {}) {
  if (frames < 4) return 0.0;
  double sum = 0.0;
  std::size_t count = 0;
  auto add = [&](std::size_t f, std::size_t j) {
    const glm::vec3 d3 =
        p[(f + 3) * n + j] - 3.0f * p[(f + 2) * n + j] + 3.0f * p[(f + 1) * n + j] - p[f * n + j];
    sum += glm::length(d3);
    ++count;
  };
  for (std::size_t f = 0; f + 3 < frames; ++f) {
    if (joints.empty()) {
      for (std::size_t j = 0; j < n; ++j) add(f, j);
    } else {
      for (int j : joints) add(f, static_cast<std::size_t>(j));
    }
  }
  return count > 0 ? sum / (static_cast<double>(count) * dt * dt * dt) : 0.0;
}

double maxJump(const std::vector<glm::vec3>& p, std::size_t frames, std::size_t n) {
  double worst = 0.0;
  for (std::size_t f = 1; f < frames; ++f) {
    for (std::size_t j = 0; j < n; ++j) {
      worst = std::max(worst, static_cast<double>(glm::distance(p[f * n + j], p[(f - 1) * n + j])));
    }
  }
  return worst;
}

// Normalised cross-correlation of the joints' velocities, solved shifted by k frames later
// than the truth; the best k refined by a parabola through its neighbours.
double velocityLag(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b,
                   std::size_t frames, std::size_t n, std::span<const int> joints, double dt) {
  if (frames < 8 || joints.empty()) return 0.0;
  const int max_shift =
      std::min(static_cast<int>(std::ceil(0.25 / dt)), static_cast<int>(frames / 4));
  auto vel = [&](const std::vector<glm::vec3>& p, std::size_t f, int j) {
    const std::size_t u = static_cast<std::size_t>(j);
    return glm::dvec3(p[(f + 1) * n + u] - p[f * n + u]);
  };
  std::vector<double> score(static_cast<std::size_t>(2 * max_shift + 1), -2.0);
  for (int k = -max_shift; k <= max_shift; ++k) {
    double ab = 0.0, aa = 0.0, bb = 0.0;
    for (std::size_t f = 0; f + 1 < frames; ++f) {
      const long g = static_cast<long>(f) + k;
      if (g < 0 || g + 1 >= static_cast<long>(frames)) continue;
      for (int j : joints) {
        const glm::dvec3 va = vel(a, f, j);
        const glm::dvec3 vb = vel(b, static_cast<std::size_t>(g), j);
        ab += glm::dot(va, vb);
        aa += glm::dot(va, va);
        bb += glm::dot(vb, vb);
      }
    }
    if (aa > 0.0 && bb > 0.0)
      score[static_cast<std::size_t>(k + max_shift)] = ab / std::sqrt(aa * bb);
  }
  const std::size_t best =
      static_cast<std::size_t>(std::max_element(score.begin(), score.end()) - score.begin());
  double shift = static_cast<double>(best) - max_shift;
  if (best > 0 && best + 1 < score.size()) {
    const double l = score[best - 1], c = score[best], r = score[best + 1];
    const double den = l - 2.0 * c + r;
    if (den < 0.0) shift += std::clamp(0.5 * (l - r) / den, -0.5, 0.5);
  }
  return shift * dt;
}

}  // namespace

std::vector<int> upperBodyJoints(const JointRoles& roles) {
  std::vector<int> out;
  for (Role r :
       {Role::kSpine, Role::kChest, Role::kUpperChest, Role::kNeck, Role::kHead, Role::kLUpperarm,
        Role::kRUpperarm, Role::kLForearm, Role::kRForearm, Role::kLHand, Role::kRHand}) {
    if (roles.has(r)) out.push_back(roles[r]);
  }
  return out;
}

std::vector<int> legJoints(const JointRoles& roles) {
  std::vector<int> out;
  for (int side = 0; side < 2; ++side) {
    for (Role r : {thighRole(side), shinRole(side), footRole(side), toesRole(side)}) {
      if (roles.has(r)) out.push_back(roles[r]);
    }
  }
  return out;
}

PostureMetrics measurePostures(const Skeleton& skeleton, const JointRoles& roles,
                               std::span<const Posture> truth, std::span<const Posture> solved,
                               double frame_time) {
  PostureMetrics m;
  const std::size_t frames = std::min(truth.size(), solved.size());
  const std::size_t n = static_cast<std::size_t>(skeleton.jointCount());
  if (frames == 0 || n == 0) return m;
  const Posed a = pose(skeleton, truth.first(frames));
  const Posed b = pose(skeleton, solved.first(frames));
  const std::vector<int> upper = upperBodyJoints(roles);
  const std::vector<int> legs = legJoints(roles);
  double pos_all = 0.0, pos_up = 0.0, rot_all = 0.0, rot_up = 0.0, pos_legs = 0.0;
  for (std::size_t f = 0; f < frames; ++f) {
    for (std::size_t j = 0; j < n; ++j) {
      pos_all += glm::distance(a.position[f * n + j], b.position[f * n + j]);
      rot_all +=
          glm::length(rotationVector(glm::inverse(a.rotation[f * n + j]) * b.rotation[f * n + j]));
    }
    for (int j : upper) {
      const std::size_t k = f * n + static_cast<std::size_t>(j);
      const double e = glm::distance(a.position[k], b.position[k]);
      pos_up += e;
      m.max_upper_m = std::max(m.max_upper_m, e);
      rot_up += glm::length(rotationVector(glm::inverse(a.rotation[k]) * b.rotation[k]));
    }
    for (int j : legs) {
      const std::size_t k = f * n + static_cast<std::size_t>(j);
      pos_legs += glm::distance(a.position[k], b.position[k]);
    }
  }
  m.frames = static_cast<int>(frames);
  m.mpjpe_all_m = pos_all / static_cast<double>(frames * n);
  m.mpjre_all_deg = glm::degrees(rot_all / static_cast<double>(frames * n));
  if (!upper.empty()) {
    m.mpjpe_upper_m = pos_up / static_cast<double>(frames * upper.size());
    m.mpjre_upper_deg = glm::degrees(rot_up / static_cast<double>(frames * upper.size()));
  }
  if (!legs.empty()) m.mpjpe_legs_m = pos_legs / static_cast<double>(frames * legs.size());
  m.jerk_truth = meanJerk(a.position, frames, n, frame_time);
  m.jerk_solved = meanJerk(b.position, frames, n, frame_time);
  m.jerk_upper_truth = meanJerk(a.position, frames, n, frame_time, upper);
  m.jerk_upper_solved = meanJerk(b.position, frames, n, frame_time, upper);
  m.max_jump_truth_m = maxJump(a.position, frames, n);
  m.max_jump_solved_m = maxJump(b.position, frames, n);
  m.lag_s = velocityLag(a.position, b.position, frames, n, upper, frame_time);
  return m;
}

}  // namespace vistel
