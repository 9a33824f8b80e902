#include "offline/build/fit.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace vistel {
namespace {

glm::vec3 centroid(std::span<const glm::vec3> pts) {
  glm::dvec3 c(0.0);
  for (const glm::vec3& p : pts) c += glm::dvec3(p);
  return glm::vec3(c / static_cast<double>(std::max<std::size_t>(pts.size(), 1)));
}

// Principal axes, largest first (columns of the returned matrix).
glm::mat3 principalAxes(std::span<const glm::vec3> pts, const glm::vec3& c) {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const glm::vec3& p : pts) {
    const Eigen::Vector3d d(p.x - c.x, p.y - c.y, p.z - c.z);
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  glm::mat3 axes;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = es.eigenvectors().col(2 - k);  // eigenvalues ascend
    axes[k] = glm::normalize(
        glm::vec3(static_cast<float>(e.x()), static_cast<float>(e.y()), static_cast<float>(e.z())));
  }
  return axes;
}

}  // namespace

ShapeFit finishFit(const Shape& shape, std::span<const glm::vec3> pts, float max_ratio) {
  ShapeFit fit;
  fit.shape = shape;
  prepareShape(fit.shape);
  double sum = 0.0;
  float biggest = 0.0f;
  for (const glm::vec3& p : pts) {
    const float d = skeletonDistance(fit.shape, p);
    sum += d;
    biggest = std::max(biggest, d);
  }
  fit.r_in = static_cast<float>(sum / static_cast<double>(std::max<std::size_t>(pts.size(), 1)));
  const float smallest = shape.kind == ShapeKind::kConeSphere ? 0.05f : 1e-4f;
  if (!(fit.r_in > smallest)) fit.r_in = smallest;
  fit.r_out = std::max(biggest, fit.r_in / max_ratio);
  return fit;
}

void principalSegment(std::span<const glm::vec3> pts, glm::vec3& a, glm::vec3& b) {
  const glm::vec3 c = centroid(pts);
  const glm::vec3 e = principalAxes(pts, c)[0];
  float t0 = INFINITY, t1 = -INFINITY;
  double radial = 0.0;
  for (const glm::vec3& p : pts) {
    const float t = glm::dot(p - c, e);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
    radial += glm::length((p - c) - t * e);
  }
  const float r =
      static_cast<float>(radial / static_cast<double>(std::max<std::size_t>(pts.size(), 1)));
  if (t1 - t0 > 2.0f * r) {
    a = c + (t0 + r) * e;
    b = c + (t1 - r) * e;
  } else {
    a = b = c + 0.5f * (t0 + t1) * e;
  }
}

ShapeFit fitSphere(std::span<const glm::vec3> pts, std::optional<glm::vec3> centre,
                   float max_ratio) {
  Shape s;
  s.kind = ShapeKind::kSphere;
  s.a = s.b = centre ? *centre : centroid(pts);
  return finishFit(s, pts, max_ratio);
}

ShapeFit fitSphylinder(std::span<const glm::vec3> pts, std::optional<glm::vec3> a,
                       std::optional<glm::vec3> b, float max_ratio) {
  Shape s;
  s.kind = ShapeKind::kSphylinder;
  if (a && b) {
    s.a = *a;
    s.b = *b;
  } else {
    principalSegment(pts, s.a, s.b);
  }
  return finishFit(s, pts, max_ratio);
}

ShapeFit fitConeSphere(std::span<const glm::vec3> pts, std::optional<glm::vec3> a,
                       std::optional<glm::vec3> b, float max_ratio) {
  Shape s;
  s.kind = ShapeKind::kConeSphere;
  if (a && b) {
    s.a = *a;
    s.b = *b;
  } else {
    principalSegment(pts, s.a, s.b);
  }
  prepareShape(s);
  // Least squares of the points' distances from the axis against the axis parameter.
  double s00 = 0, s01 = 0, s11 = 0, y0 = 0, y1 = 0, mean = 0;
  for (const glm::vec3& p : pts) {
    const float along = s.length > 0.0f ? glm::dot(p - s.a, s.axis) : 0.0f;
    const double t = s.length > 0.0f ? std::clamp(along / s.length, 0.0f, 1.0f) : 0.5;
    const double rho = glm::length(p - (s.a + static_cast<float>(t) * s.length * s.axis));
    s00 += (1 - t) * (1 - t);
    s01 += t * (1 - t);
    s11 += t * t;
    y0 += (1 - t) * rho;
    y1 += t * rho;
    mean += rho;
  }
  mean /= static_cast<double>(std::max<std::size_t>(pts.size(), 1));
  if (!(mean > 1e-4)) mean = 1e-2;
  double ra = mean, rb = mean;
  const double det = s00 * s11 - s01 * s01;
  if (det > 1e-9 * (s00 + s11) * (s00 + s11) && s.length > 0.0f) {
    ra = (y0 * s11 - y1 * s01) / det;
    rb = (y1 * s00 - y0 * s01) / det;
  }
  s.radius_a = static_cast<float>(std::clamp(ra, 0.25 * mean, 4.0 * mean));
  s.radius_b = static_cast<float>(std::clamp(rb, 0.25 * mean, 4.0 * mean));
  return finishFit(s, pts, max_ratio);
}

ShapeFit fitOffsetPolygon(std::span<const glm::vec3> pts, std::optional<glm::vec3> normal,
                          float max_ratio) {
  const glm::vec3 c = centroid(pts);
  const glm::mat3 axes = principalAxes(pts, c);
  const glm::vec3 n = normal ? glm::normalize(*normal) : axes[2];
  // In-plane axes: the largest principal axis projected into the plane, then n x u.
  glm::vec3 u = axes[0] - glm::dot(axes[0], n) * n;
  if (glm::length(u) < 1e-3f) u = axes[1] - glm::dot(axes[1], n) * n;
  u = glm::normalize(u);
  const glm::vec3 v = glm::cross(n, u);
  float x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  double thick = 0.0;
  for (const glm::vec3& p : pts) {
    const glm::vec3 d = p - c;
    x0 = std::min(x0, glm::dot(d, u));
    x1 = std::max(x1, glm::dot(d, u));
    y0 = std::min(y0, glm::dot(d, v));
    y1 = std::max(y1, glm::dot(d, v));
    thick += std::abs(glm::dot(d, n));
  }
  const float h =
      static_cast<float>(thick / static_cast<double>(std::max<std::size_t>(pts.size(), 1)));
  const auto inset = [h](float& lo, float& hi) {
    const float mid = 0.5f * (lo + hi);
    lo = std::min(lo + h, mid - 5e-4f);
    hi = std::max(hi - h, mid + 5e-4f);
  };
  inset(x0, x1);
  inset(y0, y1);
  Shape s;
  s.kind = ShapeKind::kOffsetPolygon;
  s.a = c;
  s.u = u;
  s.v = v;
  s.polygon_count = 4;
  s.polygon[0] = {x0, y0};
  s.polygon[1] = {x1, y0};
  s.polygon[2] = {x1, y1};
  s.polygon[3] = {x0, y1};
  return finishFit(s, pts, max_ratio);
}

}  // namespace vistel
