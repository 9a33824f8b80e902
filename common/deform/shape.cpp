// Skeleton distances in closed form (Singh & Parent 1994 primitives; the cone-sphere's
// ratio minimiser derived from d/dz [|p - c(z)|^2 / r(z)^2] = 0).
#include "common/deform/shape.hpp"

#include <algorithm>
#include <cmath>

namespace vistel {
namespace {

float cross2(const glm::vec2& a, const glm::vec2& b) { return a.x * b.y - a.y * b.x; }

glm::vec3 polygonVertex(const Shape& s, int i) {
  return s.a + s.polygon[static_cast<std::size_t>(i)].x * s.u +
         s.polygon[static_cast<std::size_t>(i)].y * s.v;
}

float pointPolygonDistance(const Shape& s, const glm::vec3& p) {
  const glm::vec3 r = p - s.a;
  const glm::vec2 q(glm::dot(r, s.u), glm::dot(r, s.v));
  const glm::vec2 c = closestInPolygon(s, q);
  const float h = glm::dot(r, s.normal);
  const glm::vec2 dq = q - c;
  return std::sqrt(glm::dot(dq, dq) + h * h);
}

// Distance from a segment to a convex polygon region (exact; see skeletonGap).
float segmentPolygonDistance(const glm::vec3& p0, const glm::vec3& p1, const Shape& s) {
  // The segment may pierce the polygon.
  const float h0 = glm::dot(p0 - s.a, s.normal);
  const float h1 = glm::dot(p1 - s.a, s.normal);
  if ((h0 <= 0.0f && h1 >= 0.0f) || (h0 >= 0.0f && h1 <= 0.0f)) {
    if (h0 != h1) {
      const glm::vec3 x = p0 + (h0 / (h0 - h1)) * (p1 - p0);
      if (pointPolygonDistance(s, x) <= 1e-7f) return 0.0f;
    }
  }
  // Otherwise the closest pair has an endpoint of the segment or lies on a polygon edge.
  float best = std::min(pointPolygonDistance(s, p0), pointPolygonDistance(s, p1));
  for (int i = 0; i < s.polygon_count; ++i) {
    best =
        std::min(best, segmentSegmentDistance(polygonVertex(s, i),
                                              polygonVertex(s, (i + 1) % s.polygon_count), p0, p1));
  }
  return best;
}

// An interval of line parameters, grown by union (lo > hi: empty).
struct LineInterval {
  double lo = INFINITY;
  double hi = -INFINITY;
  void add(double a, double b) {
    if (!(a <= b)) return;
    lo = std::min(lo, a);
    hi = std::max(hi, b);
  }
};

// The line p + t d inside the ball about c of radius r: |q + t d|^2 <= r^2, q = p - c.
void lineBall(const glm::dvec3& p, const glm::dvec3& d, const glm::dvec3& c, double r,
              LineInterval& out) {
  const glm::dvec3 q = p - c;
  const double a = glm::dot(d, d);
  const double b = glm::dot(q, d);
  const double disc = b * b - a * (glm::dot(q, q) - r * r);
  if (!(disc >= 0.0) || !(a > 0.0)) return;
  const double root = std::sqrt(disc);
  out.add((-b - root) / a, (-b + root) / a);
}

// The line inside the truncated cone tangent to the balls (a, ra) and (b, rb), the part of
// their hull between the two circles where it touches them. A ball of radius R(z) = ra + k z
// about the axis point at z touches the envelope in the plane x = z - R(z) k, on the circle
// of radius R(z) sqrt(1 - k^2); so between x_lo = -k ra and x_hi = L - k rb the cone's radius
// is (ra + k x) / sqrt(1 - k^2), and a point at axial x, radial distance y is inside when
// (1 - k^2) y^2 <= (ra + k x)^2 (ra + k x > 0 there). None when |k| >= 1 (one ball holds
// the other).
void lineFrustum(const glm::dvec3& p, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& e,
                 double length, double ra, double rb, LineInterval& out) {
  const double k = (rb - ra) / length;
  const double m = 1.0 - k * k;
  if (!(m > 1e-9)) return;
  const glm::dvec3 q = p - a;
  const double x0 = glm::dot(q, e);
  const double dx = glm::dot(d, e);
  // The slab between the two circles' planes.
  const double x_lo = -k * ra;
  const double x_hi = length - k * rb;
  double t1 = -INFINITY;
  double t2 = INFINITY;
  if (std::abs(dx) > 1e-12) {
    t1 = (x_lo - x0) / dx;
    t2 = (x_hi - x0) / dx;
    if (t1 > t2) std::swap(t1, t2);
  } else if (x0 < x_lo || x0 > x_hi) {
    return;
  }
  // (1 - k^2)(|q + t d|^2 - x(t)^2) - (ra + k x(t))^2 = A t^2 + 2 B t + C <= 0.
  const double r0 = ra + k * x0;
  const double qa = m * (glm::dot(d, d) - dx * dx) - k * k * dx * dx;
  const double qb = m * (glm::dot(q, d) - x0 * dx) - k * r0 * dx;
  const double qc = m * (glm::dot(q, q) - x0 * x0) - r0 * r0;
  if (std::abs(qa) < 1e-12) {  // (nearly) linear: 2 B t + C <= 0
    if (std::abs(qb) < 1e-15) {
      if (qc <= 0.0) out.add(t1, t2);
      return;
    }
    const double t = -qc / (2.0 * qb);
    if (qb > 0.0) {
      out.add(t1, std::min(t2, t));
    } else {
      out.add(std::max(t1, t), t2);
    }
    return;
  }
  const double disc = qb * qb - qa * qc;
  if (!(disc >= 0.0)) {
    if (qa < 0.0) out.add(t1, t2);  // below zero everywhere
    return;
  }
  const double root = std::sqrt(disc);
  const double s1 = std::min((-qb - root) / qa, (-qb + root) / qa);
  const double s2 = std::max((-qb - root) / qa, (-qb + root) / qa);
  if (qa > 0.0) {
    out.add(std::max(t1, s1), std::min(t2, s2));
  } else {  // outside the roots (the slab holds one nappe only)
    out.add(t1, std::min(t2, s1));
    out.add(std::max(t1, s2), t2);
  }
}

}  // namespace

bool lineInsideInterval(const Shape& s, float rho, const glm::vec3& p, const glm::vec3& dir,
                        float& t_in, float& t_out) {
  if (s.kind == ShapeKind::kOffsetPolygon || !(rho > 0.0f)) return false;
  const glm::dvec3 pd(p);
  const glm::dvec3 dd(dir);
  const glm::dvec3 a(s.a);
  const double r = rho;
  LineInterval in;
  if (s.kind == ShapeKind::kSphere) {
    lineBall(pd, dd, a, r, in);
  } else {
    const bool cone = s.kind == ShapeKind::kConeSphere;
    const double ra = cone ? r * s.radius_a : r;
    const double rb = cone ? r * s.radius_b : r;
    lineBall(pd, dd, a, ra, in);
    if (s.length > 0.0f) {
      const glm::dvec3 e(s.axis);
      const double length = s.length;
      lineBall(pd, dd, glm::dvec3(s.b), rb, in);
      lineFrustum(pd, dd, a, e, length, ra, rb, in);
    }
  }
  if (!(in.lo <= in.hi)) return false;
  t_in = static_cast<float>(in.lo);
  t_out = static_cast<float>(in.hi);
  return true;
}

glm::vec3 polygonOffset(const Shape& s, const glm::vec3& p) {
  const glm::vec3 r = p - s.a;
  const glm::vec2 c = closestInPolygon(s, glm::vec2(glm::dot(r, s.u), glm::dot(r, s.v)));
  return r - c.x * s.u - c.y * s.v;
}

void skeletonOffsets(const Shape& s, int count, const float* __restrict x,
                     const float* __restrict y, const float* __restrict z, float* __restrict ox,
                     float* __restrict oy, float* __restrict oz, float* __restrict scale) {
  // The shape's numbers as locals: the stores below could otherwise alias them, and the
  // loops would not vectorise.
  const float a0 = s.a.x, a1 = s.a.y, a2 = s.a.z;
  const float e0 = s.axis.x, e1 = s.axis.y, e2 = s.axis.z;
  const float length = s.length, k = s.cone_slope, radius_a = s.radius_a;
  const auto along_axis = [&](int i, float apx, float apy, float apz, float t) {
    ox[i] = apx - t * e0;
    oy[i] = apy - t * e1;
    oz[i] = apz - t * e2;
  };
  switch (s.kind) {
    case ShapeKind::kSphere:  // sphereOffset
      for (int i = 0; i < count; ++i) {
        ox[i] = x[i] - a0;
        oy[i] = y[i] - a1;
        oz[i] = z[i] - a2;
        scale[i] = 1.0f;
      }
      return;
    case ShapeKind::kSphylinder:  // segmentOffset
      for (int i = 0; i < count; ++i) {
        const float apx = x[i] - a0, apy = y[i] - a1, apz = z[i] - a2;
        const float t = std::clamp(apx * e0 + apy * e1 + apz * e2, 0.0f, length);
        along_axis(i, apx, apy, apz, t);
        scale[i] = 1.0f;
      }
      return;
    case ShapeKind::kConeSphere:  // coneOffset
      for (int i = 0; i < count; ++i) {
        const float apx = x[i] - a0, apy = y[i] - a1, apz = z[i] - a2;
        const float ax = apx * e0 + apy * e1 + apz * e2;
        const float y2 = std::max(apx * apx + apy * apy + apz * apz - ax * ax, 0.0f);
        const float rx = radius_a + k * ax;
        const float within = std::clamp(ax + k * y2 / rx, 0.0f, length);  // when rx > 0
        const float t = rx > 0.0f ? within : (k > 0.0f ? length : 0.0f);
        scale[i] = 1.0f / (radius_a + k * t);
        along_axis(i, apx, apy, apz, t);
      }
      return;
    case ShapeKind::kOffsetPolygon:
      if (s.rectangle) {  // rectangleOffset
        const float u0 = s.u.x, u1 = s.u.y, u2 = s.u.z, v0 = s.v.x, v1 = s.v.y, v2 = s.v.z;
        const float x0 = s.rect_min.x, x1 = s.rect_max.x, y0 = s.rect_min.y, y1 = s.rect_max.y;
        for (int i = 0; i < count; ++i) {
          const float rx = x[i] - a0, ry = y[i] - a1, rz = z[i] - a2;
          const float cx = std::clamp(rx * u0 + ry * u1 + rz * u2, x0, x1);
          const float cy = std::clamp(rx * v0 + ry * v1 + rz * v2, y0, y1);
          ox[i] = rx - cx * u0 - cy * v0;
          oy[i] = ry - cx * u1 - cy * v1;
          oz[i] = rz - cx * u2 - cy * v2;
          scale[i] = 1.0f;
        }
        return;
      }
      break;
  }
  for (int i = 0; i < count; ++i) {
    const glm::vec3 d = polygonOffset(s, glm::vec3(x[i], y[i], z[i]));
    ox[i] = d.x;
    oy[i] = d.y;
    oz[i] = d.z;
    scale[i] = 1.0f;
  }
}

void prepareShape(Shape& s) {
  const glm::vec3 d = s.b - s.a;
  s.length = glm::length(d);
  s.axis = s.length > 0.0f ? d / s.length : glm::vec3(0.0f);
  s.cone_slope = s.length > 0.0f ? (s.radius_b - s.radius_a) / s.length : 0.0f;
  s.normal = glm::cross(s.u, s.v);
  // (x0, y0), (x1, y0), (x1, y1), (x0, y1) counter-clockwise: an axis-aligned rectangle.
  const auto& q = s.polygon;
  s.rectangle = s.kind == ShapeKind::kOffsetPolygon && s.polygon_count == 4 && q[0].x < q[1].x &&
                q[0].y == q[1].y && q[1].x == q[2].x && q[1].y < q[2].y && q[2].y == q[3].y &&
                q[3].x == q[0].x;
  s.rect_min = s.rectangle ? q[0] : glm::vec2(0.0f);
  s.rect_max = s.rectangle ? q[2] : glm::vec2(0.0f);
}

Shape transformShape(const Shape& shape, const glm::mat4& xform) {
  Shape out = shape;
  out.a = glm::vec3(xform * glm::vec4(shape.a, 1.0f));
  out.b = glm::vec3(xform * glm::vec4(shape.b, 1.0f));
  if (shape.kind == ShapeKind::kOffsetPolygon) {
    const glm::mat3 rot(xform);
    const glm::vec3 u = glm::normalize(rot * shape.u);
    glm::vec3 v = rot * shape.v;
    v = glm::normalize(v - glm::dot(v, u) * u);
    out.u = u;
    out.v = v;
  }
  prepareShape(out);
  return out;
}

float pointSegmentDistance(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 ab = b - a;
  const float ll = glm::dot(ab, ab);
  const float t = ll > 0.0f ? std::clamp(glm::dot(p - a, ab) / ll, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}

float segmentSegmentDistance(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& q0,
                             const glm::vec3& q1) {
  // Closest points of two segments (clamped parametric minimisation).
  const glm::vec3 d1 = p1 - p0;
  const glm::vec3 d2 = q1 - q0;
  const glm::vec3 r = p0 - q0;
  const float a = glm::dot(d1, d1);
  const float e = glm::dot(d2, d2);
  const float f = glm::dot(d2, r);
  constexpr float kEps = 1e-12f;
  float s = 0.0f;
  float t = 0.0f;
  if (a <= kEps && e <= kEps) return glm::length(r);
  if (a <= kEps) {
    t = std::clamp(f / e, 0.0f, 1.0f);
  } else {
    const float c = glm::dot(d1, r);
    if (e <= kEps) {
      s = std::clamp(-c / a, 0.0f, 1.0f);
    } else {
      const float b = glm::dot(d1, d2);
      const float denom = a * e - b * b;
      s = denom > kEps * a * e ? std::clamp((b * f - c * e) / denom, 0.0f, 1.0f) : 0.0f;
      t = (b * s + f) / e;
      if (t < 0.0f) {
        t = 0.0f;
        s = std::clamp(-c / a, 0.0f, 1.0f);
      } else if (t > 1.0f) {
        t = 1.0f;
        s = std::clamp((b - c) / a, 0.0f, 1.0f);
      }
    }
  }
  return glm::length((p0 + s * d1) - (q0 + t * d2));
}

float metricReach(const Shape& s, float reach) {
  if (s.kind == ShapeKind::kConeSphere) return reach * std::max(s.radius_a, s.radius_b);
  return reach;
}

Bounds shapeBounds(const Shape& s, float reach) {
  Bounds box;
  const auto grow = [&box](const glm::vec3& c, float r, bool first) {
    const glm::vec3 lo = c - glm::vec3(r);
    const glm::vec3 hi = c + glm::vec3(r);
    box.min = first ? lo : glm::min(box.min, lo);
    box.max = first ? hi : glm::max(box.max, hi);
  };
  switch (s.kind) {
    case ShapeKind::kSphere:
      grow(s.a, reach, true);
      break;
    case ShapeKind::kSphylinder:
      grow(s.a, reach, true);
      grow(s.b, reach, false);
      break;
    case ShapeKind::kConeSphere:
      grow(s.a, reach * s.radius_a, true);
      grow(s.b, reach * s.radius_b, false);
      break;
    case ShapeKind::kOffsetPolygon:
      for (int i = 0; i < s.polygon_count; ++i) grow(polygonVertex(s, i), reach, i == 0);
      break;
  }
  return box;
}

float skeletonGap(const Shape& s1, const Shape& s2) {
  // Order the pair so that s1's kind <= s2's kind (point < segment < polygon).
  const auto rank = [](const Shape& s) {
    return s.kind == ShapeKind::kSphere ? 0 : (s.kind == ShapeKind::kOffsetPolygon ? 2 : 1);
  };
  if (rank(s1) > rank(s2)) return skeletonGap(s2, s1);
  const int r1 = rank(s1);
  const int r2 = rank(s2);
  if (r1 == 0 && r2 == 0) return glm::length(s1.a - s2.a);
  if (r1 == 0 && r2 == 1) return pointSegmentDistance(s1.a, s2.a, s2.b);
  if (r1 == 0) return pointPolygonDistance(s2, s1.a);
  if (r1 == 1 && r2 == 1) return segmentSegmentDistance(s1.a, s1.b, s2.a, s2.b);
  if (r1 == 1) return segmentPolygonDistance(s1.a, s1.b, s2);
  // Two convex polygons: the closest pair (or a crossing) involves an edge of one of them.
  float best = INFINITY;
  for (int i = 0; i < s1.polygon_count; ++i) {
    best =
        std::min(best, segmentPolygonDistance(polygonVertex(s1, i),
                                              polygonVertex(s1, (i + 1) % s1.polygon_count), s2));
  }
  for (int i = 0; i < s2.polygon_count; ++i) {
    best =
        std::min(best, segmentPolygonDistance(polygonVertex(s2, i),
                                              polygonVertex(s2, (i + 1) % s2.polygon_count), s1));
  }
  return best;
}

const char* shapeProblem(const Shape& s) {
  const auto finite3 = [](const glm::vec3& x) {
    return std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z);
  };
  if (!finite3(s.a) || !finite3(s.b) || !finite3(s.u) || !finite3(s.v)) {
    return "non-finite coordinates";
  }
  switch (s.kind) {
    case ShapeKind::kSphere:
    case ShapeKind::kSphylinder:
      return "";
    case ShapeKind::kConeSphere:
      if (!(s.radius_a > 0.0f) || !(s.radius_b > 0.0f) || !std::isfinite(s.radius_a) ||
          !std::isfinite(s.radius_b)) {
        return "cone-sphere radii must be positive and finite";
      }
      return "";
    case ShapeKind::kOffsetPolygon: {
      if (std::abs(glm::length(s.u) - 1.0f) > 1e-3f || std::abs(glm::length(s.v) - 1.0f) > 1e-3f ||
          std::abs(glm::dot(s.u, s.v)) > 1e-3f) {
        return "polygon axes must be unit and orthogonal";
      }
      if (s.polygon_count < 3 || s.polygon_count > kMaxPolygonVertices) {
        return "polygon must have 3..8 vertices";
      }
      for (int i = 0; i < s.polygon_count; ++i) {
        const glm::vec2 p0 = s.polygon[static_cast<std::size_t>(i)];
        const glm::vec2 p1 = s.polygon[static_cast<std::size_t>((i + 1) % s.polygon_count)];
        const glm::vec2 p2 = s.polygon[static_cast<std::size_t>((i + 2) % s.polygon_count)];
        if (!std::isfinite(p0.x) || !std::isfinite(p0.y)) return "non-finite polygon vertex";
        if (!(cross2(p1 - p0, p2 - p1) > 0.0f)) {
          return "polygon must be convex and counter-clockwise";
        }
      }
      return "";
    }
  }
  return "unknown shape kind";
}

}  // namespace vistel
