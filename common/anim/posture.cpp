#include "common/anim/posture.hpp"

#include <cassert>

namespace vistel {

Posture restPosture(const Skeleton& s) {
  Posture p;
  p.root_translation = s.rest_local.empty() ? glm::vec3(0.0f) : s.rest_local[0].translation;
  p.rotations.reserve(s.rest_local.size());
  for (const Transform& t : s.rest_local) p.rotations.push_back(t.rotation);
  return p;
}

void poseSkeleton(const Skeleton& s, const Posture& posture, std::span<glm::mat4> out_model) {
  const std::size_t n = s.names.size();
  assert(out_model.size() == n && posture.rotations.size() == n);
  assert(posture.translations.empty() || posture.translations.size() == n);
  const bool translated = !posture.translations.empty();
  for (std::size_t j = 0; j < n; ++j) {
    Transform local = s.rest_local[j];
    local.rotation = posture.rotations[j];
    if (j == 0) {
      local.translation = posture.root_translation;
    } else if (translated) {
      local.translation = posture.translations[j];
    }
    const glm::mat4 m = local.matrix();
    out_model[j] = j == 0 ? m : out_model[static_cast<std::size_t>(s.parents[j])] * m;
  }
}

void skinningMatrices(const Skeleton& s, std::span<const glm::mat4> model,
                      std::span<glm::mat4> out_skin) {
  assert(model.size() == s.inverse_bind.size() && out_skin.size() == model.size());
  for (std::size_t j = 0; j < model.size(); ++j) out_skin[j] = model[j] * s.inverse_bind[j];
}

void blendPostures(const Posture& a, const Posture& b, float t, Posture& out) {
  assert(a.rotations.size() == b.rotations.size());
  out.time = a.time + (b.time - a.time) * static_cast<double>(t);
  out.root_translation = glm::mix(a.root_translation, b.root_translation, t);
  out.rotations.resize(a.rotations.size());
  for (std::size_t j = 0; j < a.rotations.size(); ++j) {
    out.rotations[j] = glm::slerp(a.rotations[j], b.rotations[j], t);
  }
  out.translations.resize(a.translations.size() == b.translations.size() ? a.translations.size()
                                                                         : 0);
  for (std::size_t j = 0; j < out.translations.size(); ++j) {
    out.translations[j] = glm::mix(a.translations[j], b.translations[j], t);
  }
}

}  // namespace vistel
