#include "client/net/prop_models.hpp"

#include <spdlog/spdlog.h>

#include "common/scene/deform_scene.hpp"

namespace vistel::net {
namespace {

bool sameSpec(const BallSpec& a, const BallSpec& b) {
  return a.radius == b.radius && a.stiffness == b.stiffness && a.elasticity == b.elasticity &&
         a.time_constant == b.time_constant && a.reach == b.reach &&
         a.subdivisions == b.subdivisions;
}

}  // namespace

std::shared_ptr<const AvatarModel> PropModels::ball(const BallSpec& spec) {
  std::lock_guard lock(mutex_);
  for (const Entry& e : entries_) {
    if (sameSpec(e.spec, spec)) return e.model;
  }
  std::shared_ptr<const AvatarModel> model;
  if (auto made = makeBallAvatar(spec)) {
    model = std::move(*made);
  } else {
    spdlog::warn("prop: {}", made.error().message);
  }
  entries_.push_back({spec, model});
  return model;
}

void ballPosture(const glm::vec3& centre, Posture& out) {
  out.root_translation = centre;
  out.rotations.assign(1, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  out.translations.clear();
}

}  // namespace vistel::net
