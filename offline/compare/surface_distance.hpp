// Distances between two triangle surfaces: how far each lies from the other, sampled over
// every triangle (corners, edges and inside, on a fixed barycentric pattern), each sample
// measured to the nearest point of the other surface (exact point-to-triangle distance,
// found through a bounding-volume hierarchy). The symmetric Hausdorff distance is the larger of the
// two directed maxima; the mean surface distance is the area-weighted mean over both surfaces.
// Metres throughout.
#pragma once

#include <cstddef>

#include <glm/glm.hpp>

#include "offline/compare/triangle_soup.hpp"

namespace vistel {

struct DirectedDistance {
  double max = 0.0;       // the farthest sample from the other surface
  double mean = 0.0;      // area-weighted mean over the surface
  double area = 0.0;      // of this surface, m^2
  glm::vec3 worst{0.0f};  // where the farthest sample lies (on this surface)
  std::size_t samples = 0;
};

struct SurfaceDistance {
  DirectedDistance a_to_b;
  DirectedDistance b_to_a;
  double hausdorff() const { return a_to_b.max > b_to_a.max ? a_to_b.max : b_to_a.max; }
  double mean() const {
    const double area = a_to_b.area + b_to_a.area;
    return area > 0.0 ? (a_to_b.mean * a_to_b.area + b_to_a.mean * b_to_a.area) / area : 0.0;
  }
};

// Samples per triangle: (n + 1)(n + 2) / 2 for `subdivisions` n >= 1 (n = 4: 15, the
// corners included). Both soups valid (validateSoup) and with triangles; degenerate
// triangles count as points. Cost: O(samples x log triangles) for surfaces near each
// other.
SurfaceDistance surfaceDistance(const TriangleSoup& a, const TriangleSoup& b, int subdivisions = 4);

// The distance from p to the nearest point of `surface` (brute force, for tests).
double distanceToSurface(const TriangleSoup& surface, const glm::vec3& p);

}  // namespace vistel
