#include "common/anim/skeleton.hpp"

#include <cmath>
#include <unordered_set>

namespace vistel {
namespace {

bool finite(const Transform& t) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(t.translation[i]) || !std::isfinite(t.scale[i])) return false;
  }
  for (int i = 0; i < 4; ++i) {
    if (!std::isfinite(t.rotation[i])) return false;
  }
  return true;
}

}  // namespace

int Skeleton::find(std::string_view name) const {
  for (int j = 0; j < jointCount(); ++j) {
    if (names[static_cast<std::size_t>(j)] == name) return j;
  }
  return -1;
}

std::vector<int> Skeleton::children(int j) const {
  std::vector<int> out;
  for (int c = j + 1; c < jointCount(); ++c) {
    if (parents[static_cast<std::size_t>(c)] == j) out.push_back(c);
  }
  return out;
}

Status validateSkeleton(const Skeleton& s) {
  const std::size_t n = s.names.size();
  if (n == 0) return fail("skeleton has no joints");
  if (s.parents.size() != n || s.rest_local.size() != n || s.inverse_bind.size() != n) {
    return fail("skeleton arrays disagree: {} names, {} parents, {} rest transforms, {} bind", n,
                s.parents.size(), s.rest_local.size(), s.inverse_bind.size());
  }
  if (s.parents[0] != kNoParent) return fail("joint 0 '{}' must be the root", s.names[0]);
  std::unordered_set<std::string> seen;
  for (std::size_t j = 0; j < n; ++j) {
    if (s.names[j].empty()) return fail("joint {} has an empty name", j);
    if (!seen.insert(s.names[j]).second) return fail("joint name '{}' appears twice", s.names[j]);
    if (j > 0 && (s.parents[j] < 0 || static_cast<std::size_t>(s.parents[j]) >= j)) {
      return fail("joint {} '{}' has parent {}, which does not precede it", j, s.names[j],
                  s.parents[j]);
    }
    if (!finite(s.rest_local[j]))
      return fail("joint '{}' has a non-finite rest transform", s.names[j]);
  }
  return {};
}

std::vector<glm::mat4> restModelTransforms(const Skeleton& s) {
  std::vector<glm::mat4> model(s.names.size());
  for (std::size_t j = 0; j < model.size(); ++j) {
    const glm::mat4 local = s.rest_local[j].matrix();
    model[j] =
        s.parents[j] == kNoParent ? local : model[static_cast<std::size_t>(s.parents[j])] * local;
  }
  return model;
}

void computeInverseBind(Skeleton& s) {
  const std::vector<glm::mat4> model = restModelTransforms(s);
  s.inverse_bind.resize(model.size());
  for (std::size_t j = 0; j < model.size(); ++j) s.inverse_bind[j] = glm::inverse(model[j]);
}

}  // namespace vistel
