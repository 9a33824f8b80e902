// Up to four primitive fields at one point in one pass, a primitive per SIMD lane: what a
// joint vertex's own function needs (its joint, its two limbs and its bone: four fields at
// every evaluation) for about the cost of one field evaluated alone.
//
// Each lane evaluates one kernel that covers the sphere, the sphylinder, the cone-sphere and
// the rectangular offset polygon (see the kernels in shape.hpp):
//   r = p - a,  x = r . e1,  y2 = max(r . r - x^2, 0),
//   c1 = clamp(x + k y2 / (ra + k x), lo1, hi1)   (cone beyond its apex: hi1 if k > 0, else lo1)
//   c2 = clamp(r . e2, lo2, hi2),  d = r - c1 e1 - c2 e2,  scale = 1 / (ra + k c1)
// The sphere has e1 = e2 = 0; the sphylinder e1 = its axis, lo1..hi1 = 0..length, ra = 1,
// k = 0; the cone-sphere its radius ra at a and slope k; the rectangle e1, e2 = its (u, v)
// axes and lo, hi its corners, ra = 1, k = 0. Every lane makes the operations of primitiveField
// in the same order, and the terms that a shape does not have are exact zeros, so each lane
// gives primitiveField's value and gradient bit for bit (where the compiler fuses no
// multiply-adds in either; x86-64 without FMA, as built here). The Wyvill profile only; a
// general polygon, or another profile, is not packed (the caller evaluates it alone).
//
// Also one primitive's skin weight at four points, a point per lane (skinWeightLanes: pass A's
// lookups, which are independent of each other, side by side).
//
// Portable: GCC/Clang vector extensions (SSE on x86-64, NEON on AArch64, scalar elsewhere).
#pragma once

#include <cstring>

#include "common/deform/posed_primitives.hpp"

namespace vistel {

using FieldVec = float __attribute__((vector_size(16)));

// Four primitives, one per lane, as the kernel above reads them. A lane packed with nothing
// has weight 0: its field and gradient are 0.
struct FieldLanes {
  FieldVec ax, ay, az;     // a
  FieldVec e1x, e1y, e1z;  // e1
  FieldVec e2x, e2y, e2z;  // e2
  FieldVec lo1, hi1, lo2, hi2;
  FieldVec ra, k;
  FieldVec inv_r_out, weight;
};

// Puts `prim` (or nothing, when null) in lane `lane`. Returns false, leaving the lane as it
// was, for a primitive the kernel does not cover (a general polygon; a profile other than
// Wyvill's).
bool packFieldLane(const PosedPrimitive* prim, int lane, FieldLanes& lanes);

// The four fields at p (F_i as primitiveField) and their gradients, lane by lane.
struct FieldValues {
  alignas(16) float f[4];
  alignas(16) float gx[4];
  alignas(16) float gy[4];
  alignas(16) float gz[4];
};

inline void fieldLanes(const FieldLanes& l, const glm::vec3& p, FieldValues& out) {
  using Mask = int __attribute__((vector_size(16)));
  const auto clamp = [](FieldVec v, FieldVec lo, FieldVec hi) {  // as std::clamp
    const FieldVec t = v < lo ? lo : v;
    return hi < t ? hi : t;
  };
  const FieldVec zero = {0.0f, 0.0f, 0.0f, 0.0f};
  const FieldVec one = {1.0f, 1.0f, 1.0f, 1.0f};
  const FieldVec rx = p.x - l.ax;
  const FieldVec ry = p.y - l.ay;
  const FieldVec rz = p.z - l.az;
  const FieldVec x = rx * l.e1x + ry * l.e1y + rz * l.e1z;
  FieldVec y2 = (rx * rx + ry * ry + rz * rz) - x * x;
  y2 = y2 < zero ? zero : y2;
  const FieldVec rad_x = l.ra + l.k * x;
  const Mask ahead = rad_x > zero;
  const FieldVec c1_cone = clamp(x + l.k * y2 / rad_x, l.lo1, l.hi1);  // where ahead
  const FieldVec c1_apex = l.k > zero ? l.hi1 : l.lo1;
  const FieldVec c1 = ahead ? c1_cone : c1_apex;
  const FieldVec c2 = clamp(rx * l.e2x + ry * l.e2y + rz * l.e2z, l.lo2, l.hi2);
  const FieldVec scale = one / (l.ra + l.k * c1);
  const FieldVec dx = (rx - c1 * l.e1x) - c2 * l.e2x;
  const FieldVec dy = (ry - c1 * l.e1y) - c2 * l.e2y;
  const FieldVec dz = (rz - c1 * l.e1z) - c2 * l.e2z;
  const FieldVec s = scale * l.inv_r_out;
  const FieldVec s2 = s * s;
  const FieldVec u = (dx * dx + dy * dy + dz * dz) * s2;  // (distance / r_out)^2
  // Wyvill's profile in u (densityValueSquared): f = 1 and df/du = 0 at u <= 0, 0 beyond 1.
  FieldVec fu = wyvillDerivativeSquared(u);
  FieldVec f = wyvillPolynomial(u);
  const Mask centre = u <= zero;
  f = centre ? one : f;
  fu = centre ? zero : fu;
  const Mask inside = u < one;
  const FieldVec coef = 2.0f * l.weight * fu * s2;
  const FieldVec value = inside ? l.weight * f : zero;
  const FieldVec gx = inside ? coef * dx : zero;
  const FieldVec gy = inside ? coef * dy : zero;
  const FieldVec gz = inside ? coef * dz : zero;
  std::memcpy(out.f, &value, sizeof value);  // one store each
  std::memcpy(out.gx, &gx, sizeof gx);
  std::memcpy(out.gy, &gy, sizeof gy);
  std::memcpy(out.gz, &gz, sizeof gz);
}

// skinWeight (posed_primitives.hpp) of one primitive at four points, a point per lane: p, its
// skeleton offset d with its scale, and len = |d| (as std::sqrt(glm::dot(d, d))). Each lane
// makes skinWeight's operations in the same order, so the same values (where the compiler
// fuses no multiply-adds in either); the lanes' lookups overlap.
inline FieldVec skinWeightLanes(const PosedPrimitive& prim, FieldVec px, FieldVec py, FieldVec pz,
                                FieldVec dx, FieldVec dy, FieldVec dz, FieldVec scale,
                                FieldVec len) {
  using Mask = int __attribute__((vector_size(16)));
  const FieldVec zero = {0.0f, 0.0f, 0.0f, 0.0f};
  const FieldVec one = {1.0f, 1.0f, 1.0f, 1.0f};
  if (prim.skin_weight == nullptr || prim.skin_weight->n < 2) return one;
  const SkinWeightGrid& g = *prim.skin_weight;
  // The key (skinWeightKey): where the point's ray from the skeleton crosses r_out / 2.
  const FieldVec r = len * scale * prim.inv_r_out;
  const Mask on = r > zero;
  const FieldVec k = 0.5f / r - 1.0f;
  const FieldVec kx = on ? px + k * dx : px;
  const FieldVec ky = on ? py + k * dy : py;
  const FieldVec kz = on ? pz + k * dz : pz;
  // In bind space: to_bind * (key, 1), column by column as glm's mat4 * vec4.
  const glm::mat4& m = prim.to_bind;
  const auto row = [&](int i) {
    return (m[0][i] * kx + m[1][i] * ky) + (m[2][i] * kz + m[3][i] * 1.0f);
  };
  const FieldVec bx = row(0), by = row(1), bz = row(2);
  // The cell and the position in it (skinWeightAt).
  const float last = static_cast<float>(g.n - 1);
  const FieldVec lastv = zero + last;
  const auto cell = [&](FieldVec b, float lo, float hi, Mask& i, FieldVec& t) {
    FieldVec u = (b - lo) / (hi - lo) * last;
    u = u < zero ? zero : u;  // glm::clamp: min(max(u, 0), last)
    u = lastv < u ? lastv : u;
    i = __builtin_convertvector(u, Mask);
    const Mask top = {g.n - 2, g.n - 2, g.n - 2, g.n - 2};
    i = top < i ? top : i;
    t = u - __builtin_convertvector(i, FieldVec);
  };
  Mask ix, iy, iz;
  FieldVec tx, ty, tz;
  cell(bx, g.box.min.x, g.box.max.x, ix, tx);
  cell(by, g.box.min.y, g.box.max.y, iy, ty);
  cell(bz, g.box.min.z, g.box.max.z, iz, tz);
  const int n = g.n;
  const Mask base = (iz * n + iy) * n + ix;
  const float* const v = g.values.data();
  const auto at = [&](int d) {
    return FieldVec{v[base[0] + d], v[base[1] + d], v[base[2] + d], v[base[3] + d]};
  };
  const auto lerp = [](FieldVec a, FieldVec b, FieldVec s) { return a + s * (b - a); };
  const int sy = n, sz = n * n;
  const FieldVec y0 = lerp(lerp(at(0), at(1), tx), lerp(at(sy), at(sy + 1), tx), ty);
  const FieldVec y1 =
      lerp(lerp(at(sz), at(sz + 1), tx), lerp(at(sz + sy), at(sz + sy + 1), tx), ty);
  return lerp(y0, y1, tz);
}

}  // namespace vistel
