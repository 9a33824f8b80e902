// The default avatar's skin as an implicit surface: the zero set of a signed-distance
// bound built from the body plan's primitives (exact distances for cone-spheres and
// rounded boxes, a scaled bound for ellipsoids) joined by smooth unions along the part
// tree (polynomial smooth minimum). Model space, metres; negative inside.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "offline/synth/body_plan.hpp"

namespace vistel::synth {

inline constexpr int kMaxBodyShapes = 128;
inline constexpr int kMaxBodyParts = 64;

// The primitives that matter in one region (see ImplicitBody::select).
struct ShapeSubset {
  std::array<std::uint8_t, kMaxBodyShapes> ids;  // indices into the body's shapes
  int count = 0;
  std::array<std::uint8_t, kMaxBodyParts> parts;  // parts holding those shapes and their
  int part_count = 0;                             // ancestors, ascending (parents first)
};

class ImplicitBody {
 public:
  static constexpr int kMaxShapes = kMaxBodyShapes;
  static constexpr int kMaxParts = kMaxBodyParts;

  // Copies the shapes and parts of `plan` (at most kMaxShapes shapes and kMaxParts parts).
  explicit ImplicitBody(const BodyPlan& plan);

  // Field value at p, metres: zero on the skin, 1-Lipschitz (|value(p) - value(q)| <=
  // |p - q|), so no skin lies closer to p than |value(p)|. Each primitive's distance is
  // clamped at ~0.12 m (scaled with the body), so far primitives cost one bounding-sphere
  // test; near the skin (|value| < ~1 cm) the clamp changes nothing. Allocates nothing.
  float value(const glm::vec3& p) const;

  // The primitives within reach of the ball (center, radius). Evaluating only those (and
  // the parts holding them) gives, inside the ball, a 1-Lipschitz field that equals
  // value() near the skin (|value| < ~1 cm) and elsewhere has its sign and is not below
  // it: far parts can only lower the field where it is already positive. So pruning and
  // contouring may use it inside the ball, at less cost.
  void select(const glm::vec3& center, float radius, ShapeSubset& out) const;
  float value(const glm::vec3& p, const ShapeSubset& subset) const;

  // Sizing field, metres: min over primitives of (detail + slope * max(0, distance)),
  // capped at `cap`. Small near fingers, nose and toes, growing by `slope` per metre away
  // from them (so it is graded), `cap` on broad parts.
  float sizing(const glm::vec3& p, float slope, float cap) const;

  // Finite-difference gradient (four-point tetrahedral stencil, step h metres), of the
  // whole field or of a subset (p inside its ball).
  glm::vec3 gradient(const glm::vec3& p, float h = 5e-5f) const;
  glm::vec3 gradient(const glm::vec3& p, const ShapeSubset& subset, float h = 5e-5f) const;

  // The shape whose own distance at p is smallest (the body part p belongs to).
  int closestShape(const glm::vec3& p) const;

  // Moves p onto the zero set by Newton steps along the gradient (at most `iterations`,
  // stopping within 1e-6 m), with the whole field or a subset (p and the result inside
  // its ball).
  glm::vec3 project(const glm::vec3& p, int iterations = 4) const;
  glm::vec3 project(const glm::vec3& p, const ShapeSubset& subset, int iterations = 4) const;

  // Signed distance bound of one shape (exposed for tests).
  static float shapeValue(const Shape& shape, const glm::vec3& p);

 private:
  std::vector<Shape> shapes_;
  std::vector<Part> parts_;
  std::vector<std::uint8_t> all_parts_;  // 0 .. nparts-1
  std::vector<int> part_of_shape_;
  // The part tree over shape values d, for the given parts (ascending, closed under
  // taking parents; the others are absent).
  float combine(const std::array<float, kMaxShapes>& d, std::span<const std::uint8_t> parts) const;

  float cull_distance_ = 0.12f;  // primitive distances are clamped here (metres)
};

// Polynomial smooth minimum of radius k (cubic; C2): equals min(a, b) when |a - b| >= k,
// dips by at most k / 6 below it, and keeps 1-Lipschitz inputs 1-Lipschitz.
float smoothMin(float a, float b, float k);

}  // namespace vistel::synth
