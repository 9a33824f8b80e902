// Skeletons of implicit primitives (Singh & Parent 1994, "Implicit function based
// deformations of polyhedral objects"; DESIGN.md §3 "Shapes in detail"): a point
// (sphere), a segment (sphylinder), a segment with a linearly varying radius
// (cone-sphere) and a planar convex polygon (offset polygon). Each gives the distance of
// a point from its skeleton and that distance's gradient in closed form.
//
// Space: whatever space the shape's points are in (bind-pose model space in the static
// model, world space once posed), metres. A shape must be prepared (prepareShape) after
// its defining fields change; evaluation asserts nothing about outside data, so
// validateShape checks shapes that come from files.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "common/anim/skin_mesh.hpp"  // Bounds

namespace vistel {

inline constexpr int kMaxPolygonVertices = 8;

enum class ShapeKind : std::uint8_t {
  kSphere = 0,         // skeleton: the point a
  kSphylinder = 1,     // skeleton: the segment a-b (a capsule's axis)
  kConeSphere = 2,     // segment a-b with radius radius_a at a, radius_b at b, linear between
  kOffsetPolygon = 3,  // convex polygon in the plane through a spanned by u, v
};

struct Shape {
  ShapeKind kind = ShapeKind::kSphere;
  glm::vec3 a{0.0f};              // centre / segment start / polygon plane origin
  glm::vec3 b{0.0f};              // segment end (sphylinder, cone-sphere)
  glm::vec3 u{1.0f, 0.0f, 0.0f};  // polygon: unit axis in its plane
  glm::vec3 v{0.0f, 1.0f, 0.0f};  // polygon: unit axis in its plane, orthogonal to u
  float radius_a = 1.0f;          // cone-sphere: profile radius at a (metres, > 0)
  float radius_b = 1.0f;          // cone-sphere: profile radius at b (metres, > 0)
  int polygon_count = 0;          // polygon: vertex count, 3..kMaxPolygonVertices
  std::array<glm::vec2, kMaxPolygonVertices> polygon{};  // convex, counter-clockwise, in
                                                         // (u, v) coordinates about a

  // Derived by prepareShape (not stored in files).
  glm::vec3 axis{0.0f};                // unit (b - a), or 0 for a degenerate segment
  float length = 0.0f;                 // |b - a|
  float cone_slope = 0.0f;             // cone-sphere: dr/dz = (radius_b - radius_a) / length
  glm::vec3 normal{0.0f, 0.0f, 1.0f};  // polygon: u x v
  bool rectangle = false;              // polygon: an axis-aligned rectangle in (u, v)
  glm::vec2 rect_min{0.0f};            // rectangle: its corners in (u, v)
  glm::vec2 rect_max{0.0f};
};

// Fills the derived fields. Cheap; call after building or transforming a shape.
void prepareShape(Shape& shape);

// The shape carried by an affine map whose linear part is a rotation (a skinning
// transform): points by the matrix, axes by its rotation (re-orthonormalised). Prepared.
Shape transformShape(const Shape& shape, const glm::mat4& xform);

// Distance of p from the skeleton: metres for sphere, sphylinder and polygon; for the
// cone-sphere the ratio min_t |p - c(t)| / r(t) (its level sets are the scaled convex
// hulls of the two end spheres; the minimiser is in closed form). `gradient` gets the
// distance's gradient (unit length for metric shapes; zero on the skeleton itself).
inline float skeletonDistance(const Shape& shape, const glm::vec3& p,
                              glm::vec3* gradient = nullptr);

// Axis-aligned box of the points whose skeleton distance is below `reach` (the bound).
Bounds shapeBounds(const Shape& shape, float reach);

// Largest metric distance from the skeleton of a point whose skeleton distance is below
// `reach` (reach itself, or reach * max radius for the cone-sphere).
float metricReach(const Shape& shape, float reach);

// The parameters t of the line p + t dir (dir not zero; unit or not) whose points have a
// skeleton distance of at most rho > 0: [t_in, t_out]. That set is convex: a ball for the
// sphere, and for the sphylinder and the cone-sphere the convex hull of the balls about the
// segment's ends (radius rho, or rho times the end's radius for the cone-sphere's ratio), so
// the line meets it in one interval, computed in closed form: the end balls and the
// truncated cone tangent to both. Returns false where the line misses it, and for the polygon
// (not handled). Where the line grazes it the interval's ends carry the rounding of a
// quadratic's root.
bool lineInsideInterval(const Shape& shape, float rho, const glm::vec3& p, const glm::vec3& dir,
                        float& t_in, float& t_out);

// Distance between the two skeletons (cone-spheres as their axis segments), metres.
// Used by Step 1's analytic bounding-volume test. Exact for every pair of kinds.
float skeletonGap(const Shape& s1, const Shape& s2);

// Checks finite fields, positive cone radii, unit orthogonal polygon axes and a convex
// counter-clockwise polygon of 3..8 vertices. Returns a reason, or an empty string.
const char* shapeProblem(const Shape& shape);

// Distances between segments and from a point to a segment (closest points optional).
float segmentSegmentDistance(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& q0,
                             const glm::vec3& q1);
float pointSegmentDistance(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b);

// Closest point of the (convex, counter-clockwise) polygon region to q, in 2-D: q itself
// when inside, else the nearest point on an edge that q lies outside of.
inline glm::vec2 closestInPolygon(const Shape& s, const glm::vec2& q) {
  float best = INFINITY;
  glm::vec2 closest = q;
  for (int i = 0; i < s.polygon_count; ++i) {
    const glm::vec2 p0 = s.polygon[static_cast<std::size_t>(i)];
    const glm::vec2 p1 = s.polygon[static_cast<std::size_t>(i + 1 < s.polygon_count ? i + 1 : 0)];
    const glm::vec2 e = p1 - p0;
    const glm::vec2 r = q - p0;
    if (e.x * r.y - e.y * r.x >= 0.0f) continue;  // inside this edge's half-plane
    const float ee = glm::dot(e, e);
    const float t = ee > 0.0f ? std::clamp(glm::dot(r, e) / ee, 0.0f, 1.0f) : 0.0f;
    const glm::vec2 c = p0 + t * e;
    const glm::vec2 dq = q - c;
    const float d2 = glm::dot(dq, dq);
    if (d2 < best) {
      best = d2;
      closest = c;
    }
  }
  return closest;
}

// Per-kind kernels: the offset d = p - c from the skeleton's closest point c (for the
// cone-sphere, the point minimising the ratio), and the scale that turns |d| into the
// skeleton distance (1 for metric shapes, 1 / r(z) for the cone-sphere). The distance is
// |d| scale and its gradient d scale / |d|; the squared distance |d|^2 scale^2 has the
// gradient 2 d scale^2 (no square root).
inline glm::vec3 sphereOffset(const Shape& s, const glm::vec3& p) { return p - s.a; }

inline glm::vec3 segmentOffset(const Shape& s, const glm::vec3& p) {
  const glm::vec3 ap = p - s.a;
  const float t = std::clamp(glm::dot(ap, s.axis), 0.0f, s.length);
  return ap - t * s.axis;
}

inline glm::vec3 coneOffset(const Shape& s, const glm::vec3& p, float& scale) {
  // Axial coordinate x and squared radial distance y2 of p; the stationary point of
  // |p - c(z)| / r(z) is z* = x + k y2 / r(x) with k = dr/dz (when r(x) > 0). The
  // minimiser's own motion does not contribute to the gradient.
  const glm::vec3 ap = p - s.a;
  const float x = glm::dot(ap, s.axis);
  const float y2 = std::max(glm::dot(ap, ap) - x * x, 0.0f);
  const float k = s.cone_slope;
  const float rx = s.radius_a + k * x;
  float z;
  if (rx > 0.0f) {
    z = std::clamp(x + k * y2 / rx, 0.0f, s.length);
  } else {
    z = k > 0.0f ? s.length : 0.0f;  // beyond the apex: the larger end is nearest
  }
  scale = 1.0f / (s.radius_a + k * z);
  return ap - z * s.axis;
}

inline glm::vec3 rectangleOffset(const Shape& s, const glm::vec3& p) {
  const glm::vec3 r = p - s.a;
  const float cx = std::clamp(glm::dot(r, s.u), s.rect_min.x, s.rect_max.x);
  const float cy = std::clamp(glm::dot(r, s.v), s.rect_min.y, s.rect_max.y);
  return r - cx * s.u - cy * s.v;
}

glm::vec3 polygonOffset(const Shape& s, const glm::vec3& p);

// The offset from the skeleton of any shape (see the kernels above).
inline glm::vec3 skeletonOffset(const Shape& s, const glm::vec3& p, float& scale) {
  scale = 1.0f;
  switch (s.kind) {
    case ShapeKind::kSphere:
      return sphereOffset(s, p);
    case ShapeKind::kSphylinder:
      return segmentOffset(s, p);
    case ShapeKind::kConeSphere:
      return coneOffset(s, p, scale);
    case ShapeKind::kOffsetPolygon:
      if (s.rectangle) return rectangleOffset(s, p);
      break;
  }
  return polygonOffset(s, p);
}

// skeletonOffset for `count` points given as coordinate arrays, into offset coordinate
// arrays and scales: the same operations in the same order as the kernels above, so the same
// values (bit for bit where the compiler fuses no multiply-adds in either; x86-64 without FMA,
// as built here), as loops without branches that a compiler can vectorise (the cone's
// division is made for every point and used only where its radius is positive; a polygon
// other than a rectangle goes point by point). No two of the arrays may overlap.
void skeletonOffsets(const Shape& s, int count, const float* __restrict x,
                     const float* __restrict y, const float* __restrict z, float* __restrict ox,
                     float* __restrict oy, float* __restrict oz, float* __restrict scale);

inline float skeletonDistance(const Shape& s, const glm::vec3& p, glm::vec3* gradient) {
  float scale;
  const glm::vec3 d = skeletonOffset(s, p, scale);
  const float len = std::sqrt(glm::dot(d, d));
  if (gradient != nullptr) *gradient = len > 0.0f ? d * (scale / len) : glm::vec3(0.0f);
  return len * scale;
}

}  // namespace vistel
