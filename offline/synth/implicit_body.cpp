// Signed-distance primitives after Quilez's closed forms (round cone, rounded box) and a
// scaled-sphere bound for ellipsoids; smooth union by the cubic polynomial smooth minimum.
// The part tree follows Wyvill et al. 1986 / Singh & Parent 1994 in spirit: a primitive
// blends only with the parts it is attached to.
#include "offline/synth/implicit_body.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

namespace vistel::synth {
namespace {

float minComponent(const glm::vec3& v) { return std::min({v.x, v.y, v.z}); }

// A lower bound of the shape's value at p, from its bounding sphere.
float lowerBound(const Shape& s, const glm::vec3& p) {
  const float outside = glm::length(p - s.bound_center) - s.bound_radius;
  return outside > 0.0f ? s.bound_slope * outside : outside;
}

// Cone-sphere from the origin along +Y (length h), radius r1 at the origin, r2 at the end.
float roundCone(const glm::vec3& p, float h, float r1, float r2) {
  const float b = (r1 - r2) / h;
  const float a = std::sqrt(std::max(1.0f - b * b, 0.0f));
  const glm::vec2 q(std::sqrt(p.x * p.x + p.z * p.z), p.y);
  const float k = glm::dot(q, glm::vec2(-b, a));
  if (k < 0.0f) return glm::length(q) - r1;
  if (k > a * h) return glm::length(q - glm::vec2(0.0f, h)) - r2;
  return glm::dot(q, glm::vec2(a, b)) - r1;
}

// Box with outer half extents `half` and edges rounded by r.
float roundBox(const glm::vec3& p, const glm::vec3& half, float r) {
  const glm::vec3 q = glm::abs(p) - half + glm::vec3(r);
  return glm::length(glm::max(q, glm::vec3(0.0f))) + std::min(std::max({q.x, q.y, q.z}), 0.0f) - r;
}

// Gradient of f by the tetrahedral stencil: sum of k f(p + h k) / (4 h) over the four
// corners k of a regular tetrahedron.
template <typename Field>
glm::vec3 stencilGradient(const Field& f, const glm::vec3& p, float h) {
  static constexpr std::array<glm::vec3, 4> kCorners{glm::vec3(1, -1, -1), glm::vec3(-1, -1, 1),
                                                     glm::vec3(-1, 1, -1), glm::vec3(1, 1, 1)};
  glm::vec3 g(0.0f);
  for (const glm::vec3& k : kCorners) g += k * f(p + h * k);
  return g / (4.0f * h);
}

// Newton steps towards f = 0 along the gradient.
template <typename Field>
glm::vec3 newtonProject(const Field& f, const glm::vec3& p, int iterations, float h) {
  glm::vec3 q = p;
  for (int it = 0; it < iterations; ++it) {
    const float v = f(q);
    if (std::abs(v) < 1e-6f) break;
    const glm::vec3 g = stencilGradient(f, q, h);
    const float g2 = glm::dot(g, g);
    if (g2 < 1e-8f) break;
    q -= (v / g2) * g;
  }
  return q;
}

}  // namespace

float smoothMin(float a, float b, float k) {
  if (k <= 0.0f) return std::min(a, b);
  const float h = std::max(k - std::abs(a - b), 0.0f) / k;
  return std::min(a, b) - h * h * h * k * (1.0f / 6.0f);
}

ImplicitBody::ImplicitBody(const BodyPlan& plan)
    : shapes_(plan.shapes), parts_(plan.parts), cull_distance_(0.12f * plan.scale) {
  assert(shapes_.size() <= static_cast<std::size_t>(kMaxShapes));
  assert(parts_.size() <= static_cast<std::size_t>(kMaxParts));
  part_of_shape_.assign(shapes_.size(), 0);
  for (std::size_t j = 0; j < parts_.size(); ++j) {
    all_parts_.push_back(static_cast<std::uint8_t>(j));
    for (const int i : parts_[j].shapes)
      part_of_shape_[static_cast<std::size_t>(i)] = static_cast<int>(j);
  }
}

float ImplicitBody::shapeValue(const Shape& s, const glm::vec3& p) {
  const glm::vec3 q = s.to_local * (p - s.origin);
  switch (s.kind) {
    case ShapeKind::kEllipsoid:
      return (glm::length(q / s.size) - 1.0f) * minComponent(s.size);
    case ShapeKind::kRoundCone:
      return roundCone(q / s.stretch, s.size.x, s.size.y, s.size.z) * minComponent(s.stretch);
    case ShapeKind::kRoundBox:
      return roundBox(q / s.stretch, s.size, s.rounding) * minComponent(s.stretch);
  }
  return 0.0f;
}

float ImplicitBody::value(const glm::vec3& p) const {
  // Each primitive's distance, clamped at the cull distance (no need to evaluate it when
  // its bounding sphere is already that far).
  std::array<float, kMaxShapes> d;
  for (std::size_t i = 0; i < shapes_.size(); ++i) {
    const Shape& s = shapes_[i];
    d[i] = lowerBound(s, p) >= cull_distance_ ? cull_distance_
                                              : std::min(shapeValue(s, p), cull_distance_);
  }
  return combine(d, all_parts_);
}

void ImplicitBody::select(const glm::vec3& center, float radius, ShapeSubset& out) const {
  out.count = 0;
  std::array<bool, kMaxParts> active{};
  active[0] = true;
  for (std::size_t i = 0; i < shapes_.size(); ++i) {
    const Shape& s = shapes_[i];
    const float outside = glm::length(center - s.bound_center) - s.bound_radius - radius;
    if (s.bound_slope * outside < cull_distance_) {
      out.ids[static_cast<std::size_t>(out.count++)] = static_cast<std::uint8_t>(i);
      // The shape's part and every ancestor take part in the blend.
      for (int j = part_of_shape_[i]; j > 0 && !active[static_cast<std::size_t>(j)];
           j = parts_[static_cast<std::size_t>(j)].parent) {
        active[static_cast<std::size_t>(j)] = true;
      }
    }
  }
  out.part_count = 0;
  for (std::size_t j = 0; j < parts_.size(); ++j) {
    if (active[j])
      out.parts[static_cast<std::size_t>(out.part_count++)] = static_cast<std::uint8_t>(j);
  }
}

float ImplicitBody::value(const glm::vec3& p, const ShapeSubset& subset) const {
  // Primitives outside the subset are at least cull_distance_ away: clamped, they are
  // exactly cull_distance_ (as in value(p)).
  std::array<float, kMaxShapes> d;
  std::fill(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(shapes_.size()), cull_distance_);
  for (int k = 0; k < subset.count; ++k) {
    const std::size_t i = subset.ids[static_cast<std::size_t>(k)];
    d[i] = std::min(shapeValue(shapes_[i], p), cull_distance_);
  }
  return combine(d, std::span<const std::uint8_t>(subset.parts.data(),
                                                  static_cast<std::size_t>(subset.part_count)));
}

float ImplicitBody::combine(const std::array<float, kMaxShapes>& d,
                            std::span<const std::uint8_t> parts) const {
  // Each part's own blend, then children into parents (children follow their parents).
  std::array<float, kMaxParts> own;
  std::array<float, kMaxParts> tree;
  for (const std::uint8_t j : parts) {
    const Part& part = parts_[j];
    float f = d[static_cast<std::size_t>(part.shapes.front())];
    for (std::size_t k = 1; k < part.shapes.size(); ++k) {
      f = smoothMin(f, d[static_cast<std::size_t>(part.shapes[k])], part.blend);
    }
    own[j] = f;
    tree[j] = f;
  }
  for (std::size_t k = parts.size(); k-- > 1;) {
    const std::uint8_t j = parts[k];
    const Part& part = parts_[j];
    const auto parent = static_cast<std::size_t>(part.parent);
    tree[parent] = std::min(tree[parent], smoothMin(own[parent], tree[j], part.attach_blend));
  }
  return tree[0];
}

float ImplicitBody::sizing(const glm::vec3& p, float slope, float cap) const {
  float best = cap;
  for (const Shape& s : shapes_) {
    // The bounding sphere bounds the distance from below: skip shapes that cannot win.
    if (s.detail + slope * std::max(lowerBound(s, p), 0.0f) >= best) continue;
    best = std::min(best, s.detail + slope * std::max(shapeValue(s, p), 0.0f));
  }
  return best;
}

glm::vec3 ImplicitBody::gradient(const glm::vec3& p, float h) const {
  return stencilGradient([this](const glm::vec3& x) { return value(x); }, p, h);
}

glm::vec3 ImplicitBody::gradient(const glm::vec3& p, const ShapeSubset& subset, float h) const {
  return stencilGradient([&](const glm::vec3& x) { return value(x, subset); }, p, h);
}

glm::vec3 ImplicitBody::project(const glm::vec3& p, int iterations) const {
  return newtonProject([this](const glm::vec3& x) { return value(x); }, p, iterations, 5e-5f);
}

glm::vec3 ImplicitBody::project(const glm::vec3& p, const ShapeSubset& subset,
                                int iterations) const {
  return newtonProject([&](const glm::vec3& x) { return value(x, subset); }, p, iterations, 5e-5f);
}

int ImplicitBody::closestShape(const glm::vec3& p) const {
  int best = 0;
  float best_d = 1e30f;
  for (std::size_t i = 0; i < shapes_.size(); ++i) {
    const float d = shapeValue(shapes_[i], p);
    if (d < best_d) {
      best_d = d;
      best = static_cast<int>(i);
    }
  }
  return best;
}

}  // namespace vistel::synth
