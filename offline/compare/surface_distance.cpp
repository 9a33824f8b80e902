#include "offline/compare/surface_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/deform/mesh_quality.hpp"

namespace vistel {
namespace {

// A bounding-volume hierarchy over the triangles (boxes split at the median of their
// longest axis, leaves of a few triangles) for nearest-point queries by branch and bound:
// the nearer child first, a subtree skipped when its box lies farther than the best found.
class TriangleTree {
 public:
  explicit TriangleTree(const TriangleSoup& soup) : soup_(soup) {
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

  // Distance from p to the nearest triangle.
  double nearest(const glm::vec3& p) const {
    float best2 = std::numeric_limits<float>::infinity();
    std::uint32_t stack[128];
    int top = 0;
    if (!nodes_.empty()) stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (boxDistance2(n, p) >= best2) continue;
      if (n.count > 0) {
        for (std::uint32_t k = n.first; k < n.first + n.count; ++k) {
          const std::uint32_t f = order_[k];
          const glm::vec3 d =
              p - closestPointOnTriangle(p, corner(f, 0), corner(f, 1), corner(f, 2));
          best2 = std::min(best2, glm::dot(d, d));
        }
        continue;
      }
      const std::uint32_t left = n.first;
      const std::uint32_t right = n.first + 1;
      const float dl = boxDistance2(nodes_[left], p);
      const float dr = boxDistance2(nodes_[right], p);
      // Push the farther first so the nearer is searched first.
      if (top + 2 > 128) continue;  // depth is ~log2(n / kLeafSize): never reached
      if (dl < dr) {
        stack[top++] = right;
        stack[top++] = left;
      } else {
        stack[top++] = left;
        stack[top++] = right;
      }
    }
    return std::sqrt(static_cast<double>(best2));
  }

 private:
  static constexpr std::uint32_t kLeafSize = 4;
  struct Node {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
    std::uint32_t first = 0;  // leaf: first entry of order_; inner: index of the left child
    std::uint32_t count = 0;  // leaf: triangles; inner: 0
  };

  glm::vec3 corner(std::size_t f, int i) const { return soup_.positions[soup_.indices[3 * f + i]]; }

  static float boxDistance2(const Node& n, const glm::vec3& p) {
    const glm::vec3 d = glm::max(glm::max(n.lo - p, p - n.hi), glm::vec3(0.0f));
    return glm::dot(d, d);
  }

  // Fills node `index` for order_[begin, end) and builds its subtree; the two children of
  // an inner node sit next to each other (left at `first`, right at `first + 1`).
  void build(std::uint32_t index, std::uint32_t begin, std::uint32_t end) {
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

  const TriangleSoup& soup_;
  std::vector<std::uint32_t> order_;
  std::vector<glm::vec3> centre_;
  std::vector<Node> nodes_;
};

DirectedDistance directed(const TriangleSoup& from, const TriangleTree& to, int n) {
  DirectedDistance d;
  double weighted = 0.0;
  const std::size_t nt = from.indices.size() / 3;
  for (std::size_t f = 0; f < nt; ++f) {
    const glm::vec3 a = from.positions[from.indices[3 * f]];
    const glm::vec3 b = from.positions[from.indices[3 * f + 1]];
    const glm::vec3 c = from.positions[from.indices[3 * f + 2]];
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    double sum = 0.0;
    int count = 0;
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; i + j <= n; ++j) {
        const float u = static_cast<float>(i) / static_cast<float>(n);
        const float v = static_cast<float>(j) / static_cast<float>(n);
        const glm::vec3 p = a + u * (b - a) + v * (c - a);
        const double dist = to.nearest(p);
        sum += dist;
        ++count;
        if (dist > d.max) {
          d.max = dist;
          d.worst = p;
        }
      }
    }
    d.samples += static_cast<std::size_t>(count);
    weighted += area * sum / count;
    d.area += area;
  }
  d.mean = d.area > 0.0 ? weighted / d.area : 0.0;
  return d;
}

}  // namespace

SurfaceDistance surfaceDistance(const TriangleSoup& a, const TriangleSoup& b, int subdivisions) {
  const int n = std::max(1, subdivisions);
  SurfaceDistance out;
  out.a_to_b = directed(a, TriangleTree(b), n);
  out.b_to_a = directed(b, TriangleTree(a), n);
  return out;
}

double distanceToSurface(const TriangleSoup& surface, const glm::vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t + 2 < surface.indices.size(); t += 3) {
    const glm::vec3 q = closestPointOnTriangle(p, surface.positions[surface.indices[t]],
                                               surface.positions[surface.indices[t + 1]],
                                               surface.positions[surface.indices[t + 2]]);
    best = std::min(best, static_cast<double>(glm::distance(p, q)));
  }
  return best;
}

}  // namespace vistel
