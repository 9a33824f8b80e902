// Density functions f: [0,1] -> [0,1] of implicit primitives (DESIGN.md §3), with
// f(0) = 1, f(1) = 0, f'(0) = f'(1) = 0, monotone decreasing.
//
// Wyvill, McPheeters, Wyvill 1986, "Data structure for soft objects": the soft-object
// polynomial f(r) = 1 - 4/9 r^6 + 17/9 r^4 - 22/9 r^2.
// Piecewise: two cubic Hermite pieces meeting at the knee (k, 1 - k) with slope -m there;
// the slope m (0.1..3, monotone up to 3) sets how stiff the surface feels near the knee
// (Gascuel 1993 uses such per-object stiffness profiles).
#pragma once

#include <cmath>
#include <cstdint>

namespace vistel {

enum class DensityKind : std::uint8_t { kWyvill = 0, kPiecewise = 1 };

struct Density {
  DensityKind kind = DensityKind::kWyvill;
  float knee = 0.5f;   // piecewise only: r of the joint between the pieces, in [0.1, 0.9]
  float slope = 1.5f;  // piecewise only: -f'(knee), in [0.1, 3]
};

// True when the parameters are in range (kind known, knee and slope as above).
bool validDensity(const Density& density);

// The piecewise profile (out of line).
float piecewiseDensity(const Density& density, float r, float* derivative);

// Wyvill's polynomial in u = r^2, 1 - 22/9 u + 17/9 u^2 - 4/9 u^3, for u in [0, 1] (no clamp):
// the one place it is written; the profile's functions below and the packed lanes
// (field_lanes.hpp, T a vector of floats, the same operations per lane) share it.
template <typename T>
inline T wyvillPolynomial(T u) {
  return 1.0f + u * (-22.0f / 9.0f + u * (17.0f / 9.0f - 4.0f / 9.0f * u));
}
// Its derivative in u, -22/9 + 34/9 u - 12/9 u^2 (no clamp).
template <typename T>
inline T wyvillDerivativeSquared(T u) {
  return -22.0f / 9.0f + u * (34.0f / 9.0f - 12.0f / 9.0f * u);
}

// f(r) and f'(r) for r in [0, 1]; r outside is clamped (f = 1 below 0, 0 above 1, f' = 0).
// Cost: a few multiplications; no branches beyond the piece test.
inline float densityValue(const Density& d, float r, float* derivative = nullptr) {
  if (r <= 0.0f || r >= 1.0f) {
    if (derivative != nullptr) *derivative = 0.0f;
    return r <= 0.0f ? 1.0f : 0.0f;
  }
  if (d.kind != DensityKind::kWyvill) return piecewiseDensity(d, r, derivative);
  const float r2 = r * r;
  const float r4 = r2 * r2;
  if (derivative != nullptr) {
    *derivative = r * (-24.0f / 9.0f * r4 + 68.0f / 9.0f * r2 - 44.0f / 9.0f);
  }
  return wyvillPolynomial(r2);
}

// The same profile as a function of u = r^2: f and df/du (the Wyvill polynomial is one in
// r^2, so a field can skip the square root of a squared distance). u is clamped like r.
inline float densityValueSquared(const Density& d, float u, float* derivative_u = nullptr) {
  if (u <= 0.0f || u >= 1.0f) {
    if (derivative_u != nullptr) *derivative_u = 0.0f;
    return u <= 0.0f ? 1.0f : 0.0f;
  }
  if (d.kind != DensityKind::kWyvill) {
    const float r = std::sqrt(u);
    float fr = 0.0f;
    const float f = piecewiseDensity(d, r, derivative_u != nullptr ? &fr : nullptr);
    if (derivative_u != nullptr) *derivative_u = 0.5f * fr / r;
    return f;
  }
  if (derivative_u != nullptr) {
    *derivative_u = wyvillDerivativeSquared(u);
  }
  return wyvillPolynomial(u);
}

// The u in (0, 1) where the profile of densityValueSquared takes the value f in (0, 1): for
// Wyvill's, f(u) = (1 - u)^2 (1 - 4u/9), so v = 1 - u solves 4 v^3 + 5 v^2 = 9 f, increasing
// and convex in v; Newton's method from v = sqrt(9 f / 5), which lies above the root,
// converges to it monotonically. Returns false for the piecewise profile (not handled) and for
// f outside (0, 1).
bool densityInverseSquared(const Density& d, float f, double& u);

}  // namespace vistel
