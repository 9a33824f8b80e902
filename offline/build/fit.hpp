// Fitting primitive shapes to the skin vertices that define them (DESIGN.md §3
// "Fitting"): r_out = the largest skeleton distance of the points (the bound), r_in = the
// mean (the best fit), with r_in / r_out kept at most max_ratio so the surface lies well
// inside the field's support. Cone-spheres fit their end radii by least squares of the
// points' distances against the axis parameter; their r_in/r_out are then profile ratios.
#pragma once

#include <optional>
#include <span>

#include <glm/glm.hpp>

#include "common/deform/shape.hpp"

namespace vistel {

struct ShapeFit {
  Shape shape;  // prepared
  float r_in = 0.0f;
  float r_out = 0.0f;
};

// Sets r_in (mean distance) and r_out (max distance, at least r_in / max_ratio) of a
// prepared shape over the points.
ShapeFit finishFit(const Shape& shape, std::span<const glm::vec3> points, float max_ratio);

// The principal-axis segment of a point cloud: through the centroid along the largest
// axis, spanning the points' extent less the mean radial distance at each end.
void principalSegment(std::span<const glm::vec3> points, glm::vec3& a, glm::vec3& b);

// Sphere about `centre` (or the centroid). Needs >= 1 point.
ShapeFit fitSphere(std::span<const glm::vec3> points, std::optional<glm::vec3> centre,
                   float max_ratio);
// Capsule on segment a-b (or the principal segment). Needs >= 2 points.
ShapeFit fitSphylinder(std::span<const glm::vec3> points, std::optional<glm::vec3> a,
                       std::optional<glm::vec3> b, float max_ratio);
// Cone-sphere on segment a-b (or the principal segment), radii by least squares.
ShapeFit fitConeSphere(std::span<const glm::vec3> points, std::optional<glm::vec3> a,
                       std::optional<glm::vec3> b, float max_ratio);
// Rectangle in the plane through the centroid with the given normal (or the smallest
// principal axis), inset by the mean thickness. Needs >= 3 points.
ShapeFit fitOffsetPolygon(std::span<const glm::vec3> points, std::optional<glm::vec3> normal,
                          float max_ratio);

}  // namespace vistel
