#include "common/anim/skeleton.hpp"

#include <cctype>
#include <cmath>
#include <string>
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

std::string lowered(const std::string& s) {
  std::string out = s;
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
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

int findHeadJoint(const Skeleton& skeleton) {
  const int n = skeleton.jointCount();
  if (n == 0) return -1;
  // Exact canonical name, then any case, then a name containing "head".
  if (const int j = skeleton.find("head"); j >= 0) return j;
  for (int j = 0; j < n; ++j) {
    if (lowered(skeleton.names[static_cast<std::size_t>(j)]) == "head") return j;
  }
  for (int j = 0; j < n; ++j) {
    const std::string name = lowered(skeleton.names[static_cast<std::size_t>(j)]);
    const bool end_site = name.find("end") != std::string::npos ||
                          name.find("top") != std::string::npos ||
                          name.find("nub") != std::string::npos;
    if (name.find("head") != std::string::npos && !end_site) return j;
  }
  // The topmost joint at rest.
  const std::vector<glm::mat4> rest = restModelTransforms(skeleton);
  int best = 0;
  for (int j = 1; j < n; ++j) {
    if (rest[static_cast<std::size_t>(j)][3].y > rest[static_cast<std::size_t>(best)][3].y)
      best = j;
  }
  return best;
}

}  // namespace vistel
