#include "offline/compare/triangle_tree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/deform/mesh_quality.hpp"

namespace vistel {
namespace {

float boxDistance2(const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& p) {
  const glm::vec3 d = glm::max(glm::max(lo - p, p - hi), glm::vec3(0.0f));
  return glm::dot(d, d);
}

}  // namespace

TriangleTree::TriangleTree(const TriangleSoup& soup) : soup_(soup) {
  const std::size_t nt = soup.indices.size() / 3;
  order_.resize(nt);
  centre_.resize(nt);
  for (std::size_t f = 0; f < nt; ++f) {
    order_[f] = static_cast<std::uint32_t>(f);
    centre_[f] = (corner(f, 0) + corner(f, 1) + corner(f, 2)) / 3.0f;
  }
  if (nt > 0) {
    nodes_.resize(1);
    build(0, 0, static_cast<std::uint32_t>(nt));
  }
}

NearestTriangle TriangleTree::nearest(const glm::vec3& p) const {
  NearestTriangle best;
  float best2 = std::numeric_limits<float>::infinity();
  std::uint32_t stack[128];
  int top = 0;
  if (!nodes_.empty()) stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (boxDistance2(n.lo, n.hi, p) >= best2) continue;
    // A leaf: its triangles, exactly.
    if (n.count > 0) {
      for (std::uint32_t k = n.first; k < n.first + n.count; ++k) {
        const std::uint32_t f = order_[k];
        const glm::vec3 q = closestPointOnTriangle(p, corner(f, 0), corner(f, 1), corner(f, 2));
        const glm::vec3 d = p - q;
        const float d2 = glm::dot(d, d);
        if (d2 < best2) {
          best2 = d2;
          best.face = f;
          best.point = q;
        }
      }
      continue;
    }
    // An inner node: push the farther child first so the nearer is searched first.
    const std::uint32_t left = n.first;
    const std::uint32_t right = n.first + 1;
    const float dl = boxDistance2(nodes_[left].lo, nodes_[left].hi, p);
    const float dr = boxDistance2(nodes_[right].lo, nodes_[right].hi, p);
    if (top + 2 > 128) continue;  // depth is ~log2(n / kLeafSize): never reached
    if (dl < dr) {
      stack[top++] = right;
      stack[top++] = left;
    } else {
      stack[top++] = left;
      stack[top++] = right;
    }
  }
  best.distance = std::sqrt(best2);
  return best;
}

// Fills node `index` for order_[begin, end) and builds its subtree; the two children of an
// inner node sit next to each other (left at `first`, right at `first + 1`).
void TriangleTree::build(std::uint32_t index, std::uint32_t begin, std::uint32_t end) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
  glm::vec3 clo = lo, chi = hi;
  for (std::uint32_t k = begin; k < end; ++k) {
    for (int i = 0; i < 3; ++i) {
      lo = glm::min(lo, corner(order_[k], i));
      hi = glm::max(hi, corner(order_[k], i));
    }
    clo = glm::min(clo, centre_[order_[k]]);
    chi = glm::max(chi, centre_[order_[k]]);
  }
  nodes_[index].lo = lo;
  nodes_[index].hi = hi;
  if (end - begin <= kLeafSize) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    return;
  }
  const glm::vec3 extent = chi - clo;
  const int axis =
      extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(
      order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
      [&](std::uint32_t x, std::uint32_t y) { return centre_[x][axis] < centre_[y][axis]; });
  const auto children = static_cast<std::uint32_t>(nodes_.size());
  nodes_.resize(nodes_.size() + 2);
  nodes_[index].first = children;
  nodes_[index].count = 0;
  build(children, begin, mid);
  build(children + 1, mid, end);
}

}  // namespace vistel
