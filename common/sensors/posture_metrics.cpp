#include "common/sensors/posture_metrics.hpp"

#include <algorithm>

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

double meanJerk(const std::vector<glm::vec3>& p, std::size_t frames, std::size_t n, double dt) {
  if (frames < 4) return 0.0;
  double sum = 0.0;
  for (std::size_t f = 0; f + 3 < frames; ++f) {
    for (std::size_t j = 0; j < n; ++j) {
      const glm::vec3 d3 =
          p[(f + 3) * n + j] - 3.0f * p[(f + 2) * n + j] + 3.0f * p[(f + 1) * n + j] - p[f * n + j];
      sum += glm::length(d3);
    }
  }
  return sum / (static_cast<double>((frames - 3) * n) * dt * dt * dt);
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
  double pos_all = 0.0, pos_up = 0.0, rot_all = 0.0, rot_up = 0.0;
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
  }
  m.frames = static_cast<int>(frames);
  m.mpjpe_all_m = pos_all / static_cast<double>(frames * n);
  m.mpjre_all_deg = glm::degrees(rot_all / static_cast<double>(frames * n));
  if (!upper.empty()) {
    m.mpjpe_upper_m = pos_up / static_cast<double>(frames * upper.size());
    m.mpjre_upper_deg = glm::degrees(rot_up / static_cast<double>(frames * upper.size()));
  }
  m.jerk_truth = meanJerk(a.position, frames, n, frame_time);
  m.jerk_solved = meanJerk(b.position, frames, n, frame_time);
  return m;
}

}  // namespace vistel
