// TriangleTree: a bounding-volume hierarchy over a triangle soup for nearest-point queries
// (boxes split at the median of their longest axis, leaves of a few triangles; queries by
// branch and bound, the nearer child first, a subtree skipped when its box lies farther
// than the best found). Shared by surface distances (compare) and the part fields of
// synthesis.
//
// Ownership: the tree keeps a reference to the soup, which must outlive it and stay
// unchanged. Space: the soup's (metres). Cost: O(n log n) to build, about O(log n) per
// query near the surface; no allocation per query.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "offline/compare/triangle_soup.hpp"

namespace vistel {

struct NearestTriangle {
  float distance = 0.0f;   // from the query point to `point`, metres (+inf: no triangle)
  std::uint32_t face = 0;  // triangle index (indices[3 * face ...])
  glm::vec3 point{0.0f};   // the nearest point of the surface
};

class TriangleTree {
 public:
  // `soup` valid (validateSoup); may have no triangles (then every query finds none).
  explicit TriangleTree(const TriangleSoup& soup);

  NearestTriangle nearest(const glm::vec3& p) const;

 private:
  static constexpr std::uint32_t kLeafSize = 4;
  struct Node {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
    std::uint32_t first = 0;  // leaf: first entry of order_; inner: index of the left child
    std::uint32_t count = 0;  // leaf: triangles; inner: 0
  };

  glm::vec3 corner(std::size_t f, int i) const { return soup_.positions[soup_.indices[3 * f + i]]; }
  void build(std::uint32_t index, std::uint32_t begin, std::uint32_t end);

  const TriangleSoup& soup_;
  std::vector<std::uint32_t> order_;  // triangle indices, leaves' runs
  std::vector<glm::vec3> centre_;     // per triangle
  std::vector<Node> nodes_;
};

}  // namespace vistel
