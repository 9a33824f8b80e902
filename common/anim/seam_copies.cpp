#include "common/anim/seam_copies.hpp"

#include <bit>
#include <unordered_map>

namespace vistel {
namespace {

struct PositionHash {
  std::size_t operator()(const glm::vec3& p) const {
    const glm::vec3 q = p + glm::vec3(0.0f);  // -0 + 0 = +0: equal positions hash alike
    return std::bit_cast<std::uint32_t>(q.x) * 73856093u ^
           std::bit_cast<std::uint32_t>(q.y) * 19349663u ^
           std::bit_cast<std::uint32_t>(q.z) * 83492791u;
  }
};

}  // namespace

std::vector<std::uint32_t> firstCopies(std::span<const glm::vec3> positions) {
  std::unordered_map<glm::vec3, std::uint32_t, PositionHash> first;
  first.reserve(positions.size());
  std::vector<std::uint32_t> out(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) {
    out[v] = first.emplace(positions[v], static_cast<std::uint32_t>(v)).first->second;
  }
  return out;
}

}  // namespace vistel
