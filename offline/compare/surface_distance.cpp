#include "offline/compare/surface_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/deform/mesh_quality.hpp"
#include "offline/compare/triangle_tree.hpp"

namespace vistel {
namespace {

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
        const double dist = to.nearest(p).distance;
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
