// Each primitive and density function against brute force (DESIGN.md §3 "Primitive",
// "Shapes in detail"): values vs brute-force distance, gradients vs finite differences,
// on random points and at d = 0, r_in / r_out and 1.
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/deform/density.hpp"
#include "common/deform/field_lanes.hpp"
#include "common/deform/posed_primitives.hpp"
#include "common/deform/shape.hpp"

namespace vistel {
namespace {

std::vector<Density> densities() {
  return {Density{DensityKind::kWyvill, 0.5f, 1.5f}, Density{DensityKind::kPiecewise, 0.5f, 1.5f},
          Density{DensityKind::kPiecewise, 0.3f, 0.5f},
          Density{DensityKind::kPiecewise, 0.7f, 2.9f}};
}

TEST(Density, EndConditionsMonotoneAndDerivative) {
  for (const Density& d : densities()) {
    ASSERT_TRUE(validDensity(d));
    float fp0 = 1.0f, fp1 = 1.0f;
    EXPECT_FLOAT_EQ(densityValue(d, 0.0f, &fp0), 1.0f);
    EXPECT_NEAR(densityValue(d, 1.0f, &fp1), 0.0f, 1e-7f);
    EXPECT_EQ(fp0, 0.0f);
    EXPECT_EQ(fp1, 0.0f);
    // The interior formula agrees at the ends, with zero slope.
    float fa = 0.0f, fb = 0.0f;
    EXPECT_NEAR(densityValue(d, 1e-6f, &fa), 1.0f, 1e-6f);
    EXPECT_NEAR(densityValue(d, 1.0f - 1e-6f, &fb), 0.0f, 1e-6f);
    EXPECT_NEAR(fa, 0.0f, 1e-4f);
    EXPECT_NEAR(fb, 0.0f, 1e-4f);
    float prev = 1.0f;
    for (int i = 1; i < 1000; ++i) {
      const float r = static_cast<float>(i) / 1000.0f;
      float fp = 0.0f;
      const float f = densityValue(d, r, &fp);
      EXPECT_LE(f, prev + 1e-7f) << "monotone at r=" << r;
      EXPECT_GE(f, 0.0f);
      prev = f;
      const double h = 1e-3;
      const double num = (densityValue(d, static_cast<float>(r + h)) -
                          densityValue(d, static_cast<float>(r - h))) /
                         (2 * h);
      const bool near_knee = d.kind == DensityKind::kPiecewise && std::abs(r - d.knee) < 2e-3f;
      if (r > 2e-3f && r < 1.0f - 2e-3f && !near_knee) {
        EXPECT_NEAR(fp, num, 2e-3) << "r=" << r;
      }
    }
  }
}

TEST(Density, WyvillPolynomialValues) {
  const Density d;
  for (float r : {0.1f, 0.4f, 0.7f, 0.9f}) {
    const double x = r;
    const double expect =
        1 - 4.0 / 9 * std::pow(x, 6) + 17.0 / 9 * std::pow(x, 4) - 22.0 / 9 * x * x;
    EXPECT_NEAR(densityValue(d, r), expect, 1e-6);
  }
}

TEST(Density, PiecewiseStiffnessChangesSlopeAtKnee) {
  float soft = 0.0f, stiff = 0.0f;
  densityValue(Density{DensityKind::kPiecewise, 0.5f, 0.5f}, 0.5f, &soft);
  densityValue(Density{DensityKind::kPiecewise, 0.5f, 2.5f}, 0.5f, &stiff);
  EXPECT_NEAR(soft, -0.5f, 1e-5f);
  EXPECT_NEAR(stiff, -2.5f, 1e-5f);
  EXPECT_FALSE(validDensity(Density{DensityKind::kPiecewise, 0.5f, 3.5f}));
  EXPECT_FALSE(validDensity(Density{DensityKind::kPiecewise, 0.95f, 1.0f}));
}

// The inverse of Wyvill's profile in u against the profile itself, from the edge of the
// support to its centre; the piecewise profile and values outside (0, 1) are refused.
TEST(Density, WyvillInverseRecoversU) {
  const Density d;
  for (int i = 1; i < 1000; ++i) {
    const float f = static_cast<float>(i) / 1000.0f;
    double u = -1.0;
    ASSERT_TRUE(densityInverseSquared(d, f, u)) << f;
    ASSERT_GT(u, 0.0);
    ASSERT_LT(u, 1.0);
    ASSERT_NEAR(densityValueSquared(d, static_cast<float>(u)), f, 2e-6f) << f;
  }
  double u = 0.0;
  EXPECT_FALSE(densityInverseSquared(d, 0.0f, u));
  EXPECT_FALSE(densityInverseSquared(d, 1.0f, u));
  EXPECT_FALSE(densityInverseSquared(d, NAN, u));
  EXPECT_FALSE(densityInverseSquared(Density{DensityKind::kPiecewise, 0.5f, 1.5f}, 0.5f, u));
}

// Brute-force skeleton distance by dense sampling of the skeleton.
float bruteDistance(const Shape& s, const glm::vec3& p) {
  float best = INFINITY;
  switch (s.kind) {
    case ShapeKind::kSphere:
      return glm::length(p - s.a);
    case ShapeKind::kSphylinder:
    case ShapeKind::kConeSphere:
      for (int i = 0; i <= 20000; ++i) {
        const float t = static_cast<float>(i) / 20000.0f;
        const glm::vec3 c = s.a + t * (s.b - s.a);
        const float r =
            s.kind == ShapeKind::kConeSphere ? s.radius_a + t * (s.radius_b - s.radius_a) : 1.0f;
        best = std::min(best, glm::length(p - c) / r);
      }
      return best;
    case ShapeKind::kOffsetPolygon: {
      // Closest point of the plane region: the projection when inside, else the boundary.
      const glm::vec3 r = p - s.a;
      const glm::vec2 q(glm::dot(r, s.u), glm::dot(r, s.v));
      const float h = glm::dot(r, s.normal);
      bool inside = true;
      float edge = INFINITY;
      for (int i = 0; i < s.polygon_count; ++i) {
        const glm::vec2 a = s.polygon[static_cast<std::size_t>(i)];
        const glm::vec2 b = s.polygon[static_cast<std::size_t>((i + 1) % s.polygon_count)];
        const glm::vec2 e = b - a;
        if (e.x * (q.y - a.y) - e.y * (q.x - a.x) < 0.0f) inside = false;
        for (int k = 0; k <= 4000; ++k) {
          const glm::vec2 c = a + (static_cast<float>(k) / 4000.0f) * e;
          edge = std::min(edge, glm::length(q - c));
        }
      }
      const float planar = inside ? 0.0f : edge;
      return std::sqrt(planar * planar + h * h);
    }
  }
  return best;
}

std::vector<Shape> shapes() {
  std::vector<Shape> out;
  Shape s;
  s.kind = ShapeKind::kSphere;
  s.a = glm::vec3(0.1f, -0.2f, 0.3f);
  out.push_back(s);
  s.kind = ShapeKind::kSphylinder;
  s.b = glm::vec3(0.35f, 0.05f, 0.2f);
  out.push_back(s);
  s.kind = ShapeKind::kConeSphere;
  s.radius_a = 0.05f;
  s.radius_b = 0.03f;
  out.push_back(s);
  s.radius_a = 0.02f;
  s.radius_b = 0.06f;
  out.push_back(s);
  Shape poly;
  poly.kind = ShapeKind::kOffsetPolygon;
  poly.a = glm::vec3(0.0f, 1.0f, 0.1f);
  poly.u = glm::normalize(glm::vec3(1.0f, 0.2f, 0.0f));
  poly.v = glm::normalize(glm::cross(glm::vec3(0.1f, 0.3f, 1.0f), poly.u));
  poly.v = glm::normalize(poly.v - glm::dot(poly.v, poly.u) * poly.u);
  poly.polygon_count = 5;
  poly.polygon[0] = {-0.1f, -0.15f};
  poly.polygon[1] = {0.12f, -0.12f};
  poly.polygon[2] = {0.15f, 0.05f};
  poly.polygon[3] = {0.0f, 0.18f};
  poly.polygon[4] = {-0.12f, 0.06f};
  out.push_back(poly);
  for (Shape& x : out) {
    prepareShape(x);
    EXPECT_STREQ(shapeProblem(x), "");
  }
  return out;
}

glm::vec3 centre(const Shape& s) {
  return s.kind == ShapeKind::kSphere
             ? s.a
             : (s.kind == ShapeKind::kOffsetPolygon ? s.a : 0.5f * (s.a + s.b));
}

// Two shapes the kernels treat apart: a rectangular slab turned in the world, and a cone
// whose apex lies close behind its small end.
std::vector<Shape> slabAndSteepCone() {
  Shape rect;
  rect.kind = ShapeKind::kOffsetPolygon;
  rect.a = glm::vec3(0.0f, 1.2f, 0.05f);
  rect.polygon_count = 4;
  rect.polygon[0] = {-0.15f, -0.25f};
  rect.polygon[1] = {0.15f, -0.25f};
  rect.polygon[2] = {0.15f, 0.2f};
  rect.polygon[3] = {-0.15f, 0.2f};
  rect.u = glm::normalize(glm::vec3(1.0f, 0.3f, -0.2f));
  rect.v = glm::normalize(glm::cross(glm::vec3(0.2f, 0.1f, 1.0f), rect.u));
  prepareShape(rect);
  Shape steep;
  steep.kind = ShapeKind::kConeSphere;
  steep.a = glm::vec3(0.0f);
  steep.b = glm::vec3(0.0f, 0.0f, 0.1f);
  steep.radius_a = 0.01f;
  steep.radius_b = 0.08f;
  prepareShape(steep);
  return {rect, steep};
}

// The batched kernel (pass A's) against the per-point one, on random points (far ones, and
// behind a cone's apex), the skeleton's own points, and a turned slab besides the shapes
// above: the same values, bit for bit where the compiler fuses no multiply-adds (x86-64
// without FMA, as built here).
TEST(Primitive, BatchedOffsetsMatchThePerPointKernel) {
  std::vector<Shape> all = shapes();
  for (const Shape& s : slabAndSteepCone()) all.push_back(s);
  ASSERT_TRUE(all[all.size() - 2].rectangle);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  constexpr int kCount = 37;  // not a multiple of any vector width
  int exact = 0, total = 0;
  for (const Shape& s : all) {
    float x[kCount], y[kCount], z[kCount], ox[kCount], oy[kCount], oz[kCount], sc[kCount];
    for (int i = 0; i < kCount; ++i) {
      glm::vec3 p = centre(s) + glm::vec3(u(rng), u(rng), u(rng));
      if (i == 0) p = s.a;
      if (i == 1) p = s.b;
      if (i == 2) p = centre(s);
      if (i == 3) p = s.a - 0.3f * (s.b - s.a);  // behind the apex of a steep cone
      x[i] = p.x;
      y[i] = p.y;
      z[i] = p.z;
    }
    skeletonOffsets(s, kCount, x, y, z, ox, oy, oz, sc);
    for (int i = 0; i < kCount; ++i) {
      float scale = 0.0f;
      const glm::vec3 d = skeletonOffset(s, glm::vec3(x[i], y[i], z[i]), scale);
      const glm::vec3 b(ox[i], oy[i], oz[i]);
      ASSERT_LE(glm::length(b - d), 1e-6f) << "kind " << static_cast<int>(s.kind) << " point " << i;
      ASSERT_NEAR(sc[i], scale, 1e-6f * scale) << "kind " << static_cast<int>(s.kind);
      exact += (b == d && sc[i] == scale) ? 1 : 0;
      ++total;
    }
  }
#if defined(__x86_64__) && !defined(__FMA__)
  EXPECT_EQ(exact, total);
#endif
}

// The own-field lanes (a joint vertex's fields in one pass) against primitiveField, four
// primitives at a time in every order, on random points, the skeletons' own points, points
// beyond every support and behind a steep cone's apex: the same values and gradients, bit for
// bit where the compiler fuses no multiply-adds (x86-64 without FMA, as built here). An empty
// lane gives 0; a general polygon and a profile other than Wyvill's are not packed.
TEST(Primitive, FieldLanesMatchPrimitiveField) {
  std::vector<Shape> all = shapes();
  ASSERT_FALSE(all.back().rectangle);  // the general polygon
  const Shape general = all.back();
  all.pop_back();
  for (const Shape& s : slabAndSteepCone()) all.push_back(s);
  ASSERT_TRUE(all[all.size() - 2].rectangle);
  std::vector<PosedPrimitive> posed;
  for (const Shape& s : all) {
    Primitive prim;
    prim.shape = s;
    prim.r_in = s.kind == ShapeKind::kConeSphere ? 1.5f : 0.06f;
    prim.r_out = prim.r_in / 0.6f;
    prim.weight = shapeWeight(prim.density, 0.5f, prim.r_in, prim.r_out);
    posed.push_back(posePrimitive(prim, glm::mat4(1.0f)));
  }
  const int n = static_cast<int>(posed.size());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.25f, 0.25f);
  int exact = 0, total = 0;
  for (int first = 0; first < n; ++first) {
    FieldLanes lanes;
    const PosedPrimitive* in_lane[4];
    for (int k = 0; k < 4; ++k) {
      // Lane 2 empty on every other set; the others cycle through the shapes.
      in_lane[k] =
          (k == 2 && first % 2 == 0) ? nullptr : &posed[static_cast<std::size_t>((first + k) % n)];
      ASSERT_TRUE(packFieldLane(in_lane[k], k, lanes));
    }
    for (int i = 0; i < 200; ++i) {
      const PosedPrimitive& own = *in_lane[0];
      glm::vec3 p = centre(own.shape) + glm::vec3(u(rng), u(rng), u(rng));
      if (i == 0) p = own.shape.a;
      if (i == 1) p = own.shape.b;
      if (i == 2) p = own.shape.a - 0.3f * (own.shape.b - own.shape.a);
      if (i == 3) p = own.shape.a + glm::vec3(3.0f, -2.0f, 1.0f);  // beyond every support
      FieldValues out;
      fieldLanes(lanes, p, out);
      for (int k = 0; k < 4; ++k) {
        glm::vec3 g(0.0f);
        const float f = in_lane[k] != nullptr ? primitiveField(*in_lane[k], p, &g) : 0.0f;
        const glm::vec3 lg(out.gx[k], out.gy[k], out.gz[k]);
        ASSERT_NEAR(out.f[k], f, 1e-6f) << "set " << first << " lane " << k << " point " << i;
        ASSERT_LE(glm::length(lg - g), 1e-5f * std::max(1.0f, glm::length(g)))
            << "set " << first << " lane " << k << " point " << i;
        exact += (out.f[k] == f && lg == g) ? 1 : 0;
        ++total;
      }
    }
  }
#if defined(__x86_64__) && !defined(__FMA__)
  EXPECT_EQ(exact, total);
#endif
  // Not covered: the lane is left as it was.
  FieldLanes lanes;
  ASSERT_TRUE(packFieldLane(&posed[0], 1, lanes));
  Primitive poly;
  poly.shape = general;
  poly.r_in = 0.06f;
  poly.r_out = 0.1f;
  const PosedPrimitive posed_poly = posePrimitive(poly, glm::mat4(1.0f));
  EXPECT_FALSE(packFieldLane(&posed_poly, 1, lanes));
  Primitive piecewise;
  piecewise.shape = all[0];
  piecewise.density = Density{DensityKind::kPiecewise, 0.5f, 1.5f};
  const PosedPrimitive posed_piecewise = posePrimitive(piecewise, glm::mat4(1.0f));
  EXPECT_FALSE(packFieldLane(&posed_piecewise, 1, lanes));
  FieldValues out;
  fieldLanes(lanes, posed[0].shape.a, out);
  EXPECT_EQ(out.f[1], posed[0].weight);
}

// The skin weights of one primitive at four points at a time (pass A's lookups) against
// skinWeight, every shape posed by a turn and a shift, on random points, the skeleton's own
// points (no ray: the key is the point itself) and points far beyond the grid (clamped to
// its faces): the same values, bit for bit where the compiler fuses no multiply-adds (x86-64
// without FMA, as built here). Without a grid the weight is 1.
TEST(Primitive, SkinWeightLanesMatchSkinWeight) {
  const glm::mat4 xform = glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(0.3f, -0.2f, 0.5f)),
                                      0.7f, glm::normalize(glm::vec3(1.0f, 2.0f, -0.5f)));
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-0.3f, 0.3f);
  std::uniform_real_distribution<float> weight(kMinSkinWeight, 4.0f);
  int exact = 0, total = 0;
  for (const Shape& s : shapes()) {
    Primitive prim;
    prim.shape = s;
    prim.r_in = s.kind == ShapeKind::kConeSphere ? 1.5f : 0.06f;
    prim.r_out = prim.r_in / 0.6f;
    SkinWeightGrid& g = prim.skin_weight;
    g.n = 6;
    g.box = {s.a - glm::vec3(0.2f, 0.25f, 0.15f), s.a + glm::vec3(0.3f, 0.2f, 0.25f)};
    g.values.resize(static_cast<std::size_t>(g.n * g.n * g.n));
    g.max_value = 0.0f;
    for (float& w : g.values) {
      w = weight(rng);
      g.max_value = std::max(g.max_value, w);
    }
    const PosedPrimitive posed = posePrimitive(prim, xform);
    ASSERT_NE(posed.skin_weight, nullptr);
    for (int i = 0; i < 100; ++i) {
      glm::vec3 p[4], d[4];
      float scale[4], len[4];
      for (int j = 0; j < 4; ++j) {
        p[j] = centre(posed.shape) + glm::vec3(u(rng), u(rng), u(rng));
        if (i == 0 && j == 0) p[j] = posed.shape.a;  // on the skeleton
        if (i == 1 && j == 1) p[j] = posed.shape.a + glm::vec3(5.0f, -4.0f, 3.0f);  // far out
        d[j] = skeletonOffset(posed.shape, p[j], scale[j]);
        len[j] = std::sqrt(glm::dot(d[j], d[j]));
      }
      const auto lanes = [](const auto& get) { return FieldVec{get(0), get(1), get(2), get(3)}; };
      const FieldVec w = skinWeightLanes(
          posed, lanes([&](int j) { return p[j].x; }), lanes([&](int j) { return p[j].y; }),
          lanes([&](int j) { return p[j].z; }), lanes([&](int j) { return d[j].x; }),
          lanes([&](int j) { return d[j].y; }), lanes([&](int j) { return d[j].z; }),
          lanes([&](int j) { return scale[j]; }), lanes([&](int j) { return len[j]; }));
      for (int j = 0; j < 4; ++j) {
        const float expected = skinWeight(posed, p[j], d[j], scale[j]);
        ASSERT_NEAR(w[j], expected, 1e-5f * expected)
            << "kind " << static_cast<int>(s.kind) << " point " << i << " lane " << j;
        ASSERT_GE(w[j], kMinSkinWeight);
        exact += w[j] == expected ? 1 : 0;
        ++total;
      }
    }
  }
#if defined(__x86_64__) && !defined(__FMA__)
  EXPECT_EQ(exact, total);
#endif
  Primitive plain;
  plain.shape = shapes()[0];
  const PosedPrimitive no_grid = posePrimitive(plain, xform);
  const FieldVec one = skinWeightLanes(no_grid, FieldVec{}, FieldVec{}, FieldVec{}, FieldVec{},
                                       FieldVec{}, FieldVec{}, FieldVec{}, FieldVec{});
  for (int j = 0; j < 4; ++j) EXPECT_EQ(one[j], 1.0f);
}

TEST(Primitive, DistanceMatchesBruteForceAndGradientMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.3f, 0.3f);
  for (const Shape& s : shapes()) {
    for (int i = 0; i < 300; ++i) {
      const glm::vec3 p = centre(s) + glm::vec3(u(rng), u(rng), u(rng));
      glm::vec3 g;
      const float d = skeletonDistance(s, p, &g);
      const float brute = bruteDistance(s, p);
      const float scale =
          s.kind == ShapeKind::kConeSphere ? 1.0f / std::min(s.radius_a, s.radius_b) : 1.0f;
      ASSERT_NEAR(d, brute, 2e-4f * scale + 1e-3f * brute) << "kind " << static_cast<int>(s.kind);
      ASSERT_LE(d, brute + 1e-5f * scale) << "the closed form is a minimum";
      const float h = 1e-3f;
      for (int k = 0; k < 3; ++k) {
        glm::vec3 e(0.0f);
        e[k] = h;
        const float num = (skeletonDistance(s, p + e) - skeletonDistance(s, p - e)) / (2.0f * h);
        ASSERT_NEAR(g[k], num, 2e-2f * scale)
            << "kind " << static_cast<int>(s.kind) << " axis " << k;
      }
    }
  }
}

TEST(Primitive, FieldAtZeroSurfaceAndBound) {
  for (const Shape& s : shapes()) {
    for (const Density& dens : densities()) {
      Primitive prim;
      prim.shape = s;
      prim.density = dens;
      prim.r_in = s.kind == ShapeKind::kConeSphere ? 1.0f : 0.04f;
      prim.r_out = prim.r_in / 0.65f;
      prim.weight = shapeWeight(dens, 0.5f, prim.r_in, prim.r_out);
      const PosedPrimitive p = posePrimitive(prim, glm::mat4(1.0f));
      // A direction away from the skeleton, and the point on the skeleton there.
      const glm::vec3 base = s.kind == ShapeKind::kOffsetPolygon ? s.a : centre(s);
      const glm::vec3 dir = s.kind == ShapeKind::kOffsetPolygon
                                ? s.normal
                                : glm::normalize(glm::cross(
                                      s.kind == ShapeKind::kSphere ? glm::vec3(0, 0, 1) : s.axis,
                                      glm::vec3(0.3f, 1.0f, 0.1f)));
      const float unit =
          s.kind == ShapeKind::kConeSphere ? glm::mix(s.radius_a, s.radius_b, 0.5f) : 1.0f;
      // Far along dir the closed form may pick another skeleton point; find distance t
      // with skeletonDistance == target by bisection along the ray.
      const auto at_ratio = [&](float ratio) {
        float lo = 0.0f, hi = 2.0f * prim.r_out * unit;
        for (int it = 0; it < 60; ++it) {
          const float mid = 0.5f * (lo + hi);
          (skeletonDistance(s, base + mid * dir) < ratio * prim.r_out ? lo : hi) = mid;
        }
        return base + 0.5f * (lo + hi) * dir;
      };
      glm::vec3 g;
      EXPECT_NEAR(primitiveField(p, base, &g), prim.weight, 1e-5f);  // d = 0
      EXPECT_NEAR(glm::length(g), 0.0f, 1e-3f * prim.weight / (prim.r_out * unit));
      EXPECT_NEAR(primitiveField(p, at_ratio(prim.r_in / prim.r_out)), 0.5f, 1e-4f);  // surface
      EXPECT_NEAR(primitiveField(p, at_ratio(1.0f) + 1e-5f * dir), 0.0f, 1e-6f);      // bound
      // Gradient vs finite differences at d = r_in / r_out and at random d in (0, 1).
      for (float ratio : {prim.r_in / prim.r_out, 0.2f, 0.5f, 0.9f}) {
        const glm::vec3 q = at_ratio(ratio);
        primitiveField(p, q, &g);
        const float h = 1e-4f * unit;
        for (int k = 0; k < 3; ++k) {
          glm::vec3 e(0.0f);
          e[k] = h;
          const float num = (primitiveField(p, q + e) - primitiveField(p, q - e)) / (2.0f * h);
          EXPECT_NEAR(g[k], num, 2e-2f * std::max(1.0f, glm::length(g))) << "ratio " << ratio;
        }
      }
    }
  }
}

TEST(Primitive, ConeSphereLevelSetsAreScaledHullsOfEndSpheres) {
  Shape s;
  s.kind = ShapeKind::kConeSphere;
  s.a = glm::vec3(0.0f);
  s.b = glm::vec3(0.3f, 0.0f, 0.0f);
  s.radius_a = 0.05f;
  s.radius_b = 0.025f;
  prepareShape(s);
  // On the end spheres scaled by 1: ratio 1 (beyond the ends, on their outer caps).
  EXPECT_NEAR(skeletonDistance(s, glm::vec3(-0.05f, 0.0f, 0.0f)), 1.0f, 1e-5f);
  EXPECT_NEAR(skeletonDistance(s, glm::vec3(0.325f, 0.0f, 0.0f)), 1.0f, 1e-5f);
  // On the tangent cone between them: the hull's side at ratio 1.
  const float sin_a = (s.radius_a - s.radius_b) / 0.3f;
  const float cos_a = std::sqrt(1.0f - sin_a * sin_a);
  const glm::vec3 touch_a(s.radius_a * sin_a, s.radius_a * cos_a, 0.0f);
  const glm::vec3 touch_b =
      glm::vec3(0.3f, 0.0f, 0.0f) + glm::vec3(s.radius_b * sin_a, s.radius_b * cos_a, 0.0f);
  EXPECT_NEAR(skeletonDistance(s, 0.5f * (touch_a + touch_b)), 1.0f, 1e-4f);
  // Scaling: ratio 2 on the doubled hull.
  EXPECT_NEAR(skeletonDistance(s, glm::vec3(-0.1f, 0.0f, 0.0f)), 2.0f, 1e-5f);
}

// The interval of a line inside a level set of the skeleton distance (the hard contact's
// closed form) against the distance sampled along the line: every sampled point inside lies
// in the interval, every one well within it is inside, and its ends are on the level set. On
// random lines near each shape, lines along a cone's axis and through the apex side of a
// steep cone, and a segment of length 0; the polygon is not handled.
TEST(Primitive, LineInsideIntervalMatchesSampledDistance) {
  std::vector<Shape> all;
  for (const Shape& s : shapes()) {
    if (s.kind != ShapeKind::kOffsetPolygon) all.push_back(s);
  }
  all.push_back(slabAndSteepCone()[1]);
  Shape point_cone = all.back();
  point_cone.b = point_cone.a;
  prepareShape(point_cone);
  all.push_back(point_cone);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  constexpr float kStep = 2e-4f;
  int hits = 0, misses = 0;
  for (Shape s : all) {
    prepareShape(s);
    const float unit = s.kind == ShapeKind::kConeSphere ? std::max(s.radius_a, s.radius_b) : 1.0f;
    for (int line = 0; line < 300; ++line) {
      const float rho = (0.3f + 0.7f * std::abs(u(rng))) * 0.08f / unit;
      glm::vec3 p = centre(s) + 0.12f * glm::vec3(u(rng), u(rng), u(rng));
      glm::vec3 dir = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(1e-3f));
      if (line == 0 && s.length > 0.0f) dir = s.axis;  // along the axis, from the middle
      if (line == 1 && s.length > 0.0f) {
        p = s.a - 0.05f * s.axis + 0.001f * glm::vec3(u(rng), u(rng), u(rng));
        dir = glm::normalize(s.axis + 0.2f * glm::vec3(u(rng), u(rng), u(rng)));
      }
      float t_in = 0.0f, t_out = 0.0f;
      const bool hit = lineInsideInterval(s, rho, p, dir, t_in, t_out);
      hits += hit ? 1 : 0;
      misses += hit ? 0 : 1;
      if (hit) {
        ASSERT_LE(t_in, t_out);
        for (const float t : {t_in, t_out}) {
          const float d = skeletonDistance(s, p + t * dir);
          ASSERT_NEAR(d, rho, 2e-5f / unit + 1e-5f * rho)
              << "kind " << static_cast<int>(s.kind) << " line " << line;
        }
      }
      for (float t = -0.6f; t <= 0.6f; t += kStep) {
        const float d = skeletonDistance(s, p + t * dir);
        if (d <= rho) {
          ASSERT_TRUE(hit) << "kind " << static_cast<int>(s.kind) << " line " << line << " t " << t;
          ASSERT_GE(t, t_in - kStep) << "kind " << static_cast<int>(s.kind) << " line " << line;
          ASSERT_LE(t, t_out + kStep) << "kind " << static_cast<int>(s.kind) << " line " << line;
        } else if (hit && t > t_in + kStep && t < t_out - kStep) {
          FAIL() << "outside within the interval: kind " << static_cast<int>(s.kind) << " line "
                 << line << " t " << t << " distance " << d << " rho " << rho;
        }
      }
    }
  }
  EXPECT_GT(hits, 300);
  EXPECT_GT(misses, 50);
  float t_in = 0.0f, t_out = 0.0f;
  EXPECT_FALSE(lineInsideInterval(slabAndSteepCone()[0], 0.05f, glm::vec3(0.0f),
                                  glm::vec3(1.0f, 0.0f, 0.0f), t_in, t_out));
}

TEST(Primitive, SkeletonGapMatchesBruteForce) {
  const std::vector<Shape> all = shapes();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.2f, 0.2f);
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = 0; j < all.size(); ++j) {
      for (int trial = 0; trial < 10; ++trial) {
        Shape a = all[i];
        Shape b = transformShape(
            all[j], glm::translate(glm::mat4(1.0f), glm::vec3(u(rng), u(rng), u(rng))));
        const float gap = skeletonGap(a, b);
        // Brute force: sample b's skeleton, take a's metric distance (cones as segments).
        Shape am = a, bm = b;
        if (am.kind == ShapeKind::kConeSphere) am.kind = ShapeKind::kSphylinder;
        if (bm.kind == ShapeKind::kConeSphere) bm.kind = ShapeKind::kSphylinder;
        float brute = INFINITY;
        if (bm.kind == ShapeKind::kOffsetPolygon) {
          for (int x = -60; x <= 60; ++x) {
            for (int y = -60; y <= 60; ++y) {
              const glm::vec2 q(0.2f * x / 60.0f, 0.2f * y / 60.0f);
              const glm::vec3 p = bm.a + q.x * bm.u + q.y * bm.v;
              if (skeletonDistance(bm, p) > 1e-6f) continue;
              brute = std::min(brute, skeletonDistance(am, p));
            }
          }
          for (int e = 0; e < bm.polygon_count; ++e) {
            const glm::vec2 p0 = bm.polygon[static_cast<std::size_t>(e)],
                            p1 = bm.polygon[static_cast<std::size_t>((e + 1) % bm.polygon_count)];
            for (int k = 0; k <= 400; ++k) {
              const glm::vec2 q = glm::mix(p0, p1, k / 400.0f);
              brute = std::min(brute, skeletonDistance(am, bm.a + q.x * bm.u + q.y * bm.v));
            }
          }
        } else if (bm.kind == ShapeKind::kSphere) {
          brute = skeletonDistance(am, bm.a);
        } else {
          for (int k = 0; k <= 4000; ++k) {
            brute = std::min(brute, skeletonDistance(am, glm::mix(bm.a, bm.b, k / 4000.0f)));
          }
        }
        ASSERT_LE(gap, brute + 1e-4f) << i << " vs " << j;
        ASSERT_NEAR(gap, brute, 5e-3f) << i << " vs " << j;
      }
    }
  }
}

}  // namespace
}  // namespace vistel
