// Wyvill et al. 1986 soft-object polynomial and a piecewise cubic Hermite profile.
#include "common/deform/density.hpp"

#include <algorithm>
#include <cmath>

namespace vistel {
namespace {

// Cubic Hermite on [r0, r0 + h] through (p0, slope m0) and (p1, slope m1).
float hermite(float r, float r0, float h, float p0, float m0, float p1, float m1,
              float* derivative) {
  const float t = (r - r0) / h;
  const float t2 = t * t;
  const float t3 = t2 * t;
  const float h00 = 2.0f * t3 - 3.0f * t2 + 1.0f;
  const float h10 = t3 - 2.0f * t2 + t;
  const float h01 = -2.0f * t3 + 3.0f * t2;
  const float h11 = t3 - t2;
  if (derivative != nullptr) {
    const float d00 = 6.0f * t2 - 6.0f * t;
    const float d10 = 3.0f * t2 - 4.0f * t + 1.0f;
    const float d01 = -6.0f * t2 + 6.0f * t;
    const float d11 = 3.0f * t2 - 2.0f * t;
    *derivative = (d00 * p0 + d01 * p1) / h + d10 * m0 + d11 * m1;
  }
  return h00 * p0 + h10 * h * m0 + h01 * p1 + h11 * h * m1;
}

}  // namespace

bool validDensity(const Density& d) {
  switch (d.kind) {
    case DensityKind::kWyvill:
      return true;
    case DensityKind::kPiecewise:
      return std::isfinite(d.knee) && std::isfinite(d.slope) && d.knee >= 0.1f && d.knee <= 0.9f &&
             d.slope >= 0.1f && d.slope <= 3.0f;
  }
  return false;
}

bool densityInverseSquared(const Density& d, float f, double& u) {
  if (d.kind != DensityKind::kWyvill || !(f > 0.0f && f < 1.0f)) return false;
  const double target = 9.0 * static_cast<double>(f);
  double v = std::min(1.0, std::sqrt(target / 5.0));
  for (int i = 0; i < 8; ++i) {
    const double step = (v * v * (4.0 * v + 5.0) - target) / (v * (12.0 * v + 10.0));
    v -= step;
    if (!(std::abs(step) > 1e-13)) break;
  }
  u = 1.0 - v;
  return u > 0.0 && u < 1.0;
}

float piecewiseDensity(const Density& d, float r, float* derivative) {
  // (0, 1, slope 0) -> (k, 1 - k, slope -m) -> (1, 0, slope 0).
  const float k = d.knee;
  if (r < k) return hermite(r, 0.0f, k, 1.0f, 0.0f, 1.0f - k, -d.slope, derivative);
  return hermite(r, k, 1.0f - k, 1.0f - k, -d.slope, 0.0f, 0.0f, derivative);
}

}  // namespace vistel
