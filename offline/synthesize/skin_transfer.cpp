#include "offline/synthesize/skin_transfer.hpp"

#include <algorithm>

namespace vistel {
namespace {

TriangleSoup soupOf(const SkinMesh& skin) {
  TriangleSoup soup;
  soup.positions = skin.positions;
  soup.indices = skin.indices;
  return soup;
}

void add(Influences& into, std::uint16_t joint, float weight) {
  if (weight <= 0.0f) return;
  for (auto& [j, w] : into) {
    if (j == joint) {
      w += weight;
      return;
    }
  }
  into.emplace_back(joint, weight);
}

}  // namespace

// soup_ is declared before tree_, so the tree is built over the finished copy.
SkinTransfer::SkinTransfer(const SkinMesh& skin) : skin_(skin), soup_(soupOf(skin)), tree_(soup_) {}

Influences SkinTransfer::at(const glm::vec3& p) const {
  const NearestTriangle hit = tree_.nearest(p);
  Influences out;
  if (soup_.indices.empty()) return out;
  const std::uint32_t* corner = &soup_.indices[3 * static_cast<std::size_t>(hit.face)];
  // Barycentric coordinates of the nearest point.
  const glm::vec3& a = soup_.positions[corner[0]];
  const glm::vec3 e0 = soup_.positions[corner[1]] - a, e1 = soup_.positions[corner[2]] - a;
  const glm::vec3 e2 = hit.point - a;
  const float d00 = glm::dot(e0, e0), d01 = glm::dot(e0, e1), d11 = glm::dot(e1, e1);
  const float d20 = glm::dot(e2, e0), d21 = glm::dot(e2, e1);
  const float denom = d00 * d11 - d01 * d01;
  float v = 1.0f / 3.0f, w = 1.0f / 3.0f;
  if (denom > 1e-20f) {
    v = std::clamp((d11 * d20 - d01 * d21) / denom, 0.0f, 1.0f);
    w = std::clamp((d00 * d21 - d01 * d20) / denom, 0.0f, 1.0f - v);
  }
  const float bary[3] = {1.0f - v - w, v, w};
  const auto k = static_cast<std::size_t>(skin_.influences);
  for (int c = 0; c < 3; ++c) {
    for (std::size_t s = 0; s < k; ++s) {
      const std::size_t slot = corner[c] * k + s;
      add(out, skin_.joints[slot], bary[c] * skin_.weights[slot]);
    }
  }
  return out;
}

Influences blendInfluences(const Influences& a, const Influences& b, float t) {
  Influences out;
  for (const auto& [j, w] : a) add(out, j, (1.0f - t) * w);
  for (const auto& [j, w] : b) add(out, j, t * w);
  return out;
}

void storeInfluences(const Influences& in, std::uint16_t fallback_joint,
                     std::span<std::uint16_t> joints, std::span<float> weights) {
  Influences sorted = in;
  std::sort(sorted.begin(), sorted.end(), [](const auto& x, const auto& y) {
    return x.second != y.second ? x.second > y.second : x.first < y.first;
  });
  const std::size_t k = joints.size();
  if (sorted.size() > k) sorted.resize(k);
  float sum = 0.0f;
  for (const auto& [j, w] : sorted) sum += w;
  for (std::size_t s = 0; s < k; ++s) {
    joints[s] = 0;
    weights[s] = 0.0f;
  }
  if (!(sum > 0.0f)) {
    joints[0] = fallback_joint;
    weights[0] = 1.0f;
    return;
  }
  for (std::size_t s = 0; s < sorted.size(); ++s) {
    joints[s] = sorted[s].first;
    weights[s] = sorted[s].second / sum;
  }
}

}  // namespace vistel
