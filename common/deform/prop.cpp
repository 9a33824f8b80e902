#include "common/deform/prop.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>

#include "common/deform/calibrate.hpp"
#include "common/deform/posed_primitives.hpp"

namespace vistel {
namespace {

void icosphere(float radius, int levels, SkinMesh& m) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<glm::vec3> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                              {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                              {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::uint32_t> f = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7, 10, 0, 10, 11,
                                  1, 5,  9, 5, 11, 4,  11, 10, 2,  10, 7, 6,  7, 1,  8,
                                  3, 9,  4, 3, 4,  2,  3,  2,  6,  3,  6, 8,  3, 8,  9,
                                  4, 9,  5, 2, 4,  11, 6,  2,  10, 8,  6, 7,  9, 8,  1};
  for (glm::vec3& x : p) x = glm::normalize(x);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back(glm::normalize(p[a] + p[b]));
      const auto i = static_cast<std::uint32_t>(p.size() - 1);
      mid.emplace(key, i);
      return i;
    };
    std::vector<std::uint32_t> g;
    for (std::size_t i = 0; i < f.size(); i += 3) {
      const std::uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
      const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      g.insert(g.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f.swap(g);
  }
  m.positions.clear();
  m.normals.clear();
  for (const glm::vec3& x : p) {
    m.positions.push_back(radius * x);
    m.normals.push_back(x);
  }
  m.indices = f;
  m.influences = 1;
  m.joints.assign(p.size(), 0);
  m.weights.assign(p.size(), 1.0f);
}

// Series stiffness of two materials (Pa/m), rigid ones yielding nothing, capped.
float seriesStiffness(float k_a, float k_b, float cap) {
  const bool rigid_a = std::isinf(k_a);
  const bool rigid_b = std::isinf(k_b);
  float k;
  if (rigid_a && rigid_b) {
    k = cap;
  } else if (rigid_a) {
    k = k_b;
  } else if (rigid_b) {
    k = k_a;
  } else {
    k = k_a * k_b / (k_a + k_b);
  }
  return std::min(k, cap);
}

// One sampled contact of the ball's surface with a surface of local radius r_s.
struct Touch {
  float depth = 0.0f;
  glm::vec3 normal{0.0f, 1.0f, 0.0f};  // from the surface towards the ball
  glm::vec3 closest{0.0f};             // nearest point of the primitive's skeleton
  float reduced_radius = 0.0f;         // R* = R r_s / (R + r_s)
  float core_depth = INFINITY;         // depth where the rigid core begins
};

// Directions of the ball's lower cap sampled by capDepth: rings at these angles from the
// point nearest the primitive's skeleton, kCapAzimuths points each.
constexpr float kCapAngles[] = {0.1396f, 0.2793f, 0.4189f, 0.5585f, 0.6981f, 0.8378f};  // 8..48 deg
constexpr int kCapAzimuths = 16;

// How deep the deepest sampled point of the ball's cap facing the skeleton (direction
// -normal) lies inside the primitive's skin, measured along that point's own ray from the
// skeleton (metres; negative: all outside).
float capDepth(const PosedPrimitive& p, const glm::vec3& c, float r, const glm::vec3& normal) {
  const glm::vec3 helper =
      std::abs(normal.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  const glm::vec3 e1 = glm::normalize(glm::cross(normal, helper));
  const glm::vec3 e2 = glm::cross(normal, e1);
  float deepest = -INFINITY;
  for (const float angle : kCapAngles) {
    const float ca = std::cos(angle), sa = std::sin(angle);
    for (int k = 0; k < kCapAzimuths; ++k) {
      const float b = 2.0f * std::numbers::pi_v<float> * static_cast<float>(k) / kCapAzimuths;
      const glm::vec3 q = c + r * (-ca * normal + sa * (std::cos(b) * e1 + std::sin(b) * e2));
      float sc;
      const glm::vec3 d = skeletonOffset(p.shape, q, sc);
      // Skeleton units to metres: 1 for metric shapes, the local radius for cone-spheres.
      const float units = sc > 0.0f ? 1.0f / sc : 1.0f;
      const float w = skinWeight(p, q, d, sc);
      const float depth = skinSurfaceDistance(p, w) * units - std::sqrt(glm::dot(d, d));
      deepest = std::max(deepest, depth);
    }
  }
  return deepest;
}

// Contact of the ball (centre c, radius r) with one posed primitive's skin: its iso-surface
// w_i F_i = T, w_i the calibrated skin weight (the bare F_i = T without one).
bool touchPrimitive(const PosedPrimitive& p, const glm::vec3& c, float r, float core_fraction,
                    Touch& t) {
  if (!p.collides) return false;
  const Bounds& b = p.bounds;  // the support contains the surface
  if (c.x < b.min.x - r || c.x > b.max.x + r || c.y < b.min.y - r || c.y > b.max.y + r ||
      c.z < b.min.z - r || c.z > b.max.z + r) {
    return false;
  }
  glm::vec3 g;
  const float s = skeletonDistance(p.shape, c, &g);
  const float gl = std::sqrt(glm::dot(g, g));
  // Metric shapes have |g| = 1; a cone-sphere's distance is a ratio, |g| = 1 / local radius.
  float scale = 1.0f;
  if (p.shape.kind == ShapeKind::kConeSphere) {
    scale = gl > 0.0f ? 1.0f / gl : std::max(p.shape.radius_a, p.shape.radius_b);
  }
  const float dist = s * scale;
  // The surface the body's skin makes on the ray through the ball's centre (its calibrated
  // skin weight there), so the ball meets the skin rather than the bare primitive.
  const float r_s = skinSurfaceDistance(p, skinWeight(p, c)) * scale;
  float depth = r_s + r - dist;
  const glm::vec3 normal = gl > 0.0f ? g / gl : glm::vec3(0.0f, 1.0f, 0.0f);
  // The skin is not an offset surface: where it stands out beside the centre's ray (a
  // nose, a heel, a shoulder blade) the ball meets it first. Sample the ball's lower cap
  // and take the deepest point inside the skin on its own ray.
  if (p.skin_weight != nullptr && dist - r < p.reach)
    depth = std::max(depth, capDepth(p, c, r, normal));
  if (!(depth > 0.0f)) return false;
  t.depth = depth;
  t.normal = normal;
  t.closest = c - dist * t.normal;
  t.reduced_radius = p.shape.kind == ShapeKind::kOffsetPolygon ? r : r * r_s / (r + r_s);
  t.core_depth = (1.0f - core_fraction) * r_s;
  return true;
}

// Where the skeleton point `closest` of posed primitive `now` was on `before` (the same
// primitive posed earlier): the same parameters along the segment or in the polygon.
glm::vec3 earlierPoint(const PosedPrimitive& now, const PosedPrimitive& before,
                       const glm::vec3& closest) {
  const Shape& a = now.shape;
  const Shape& b = before.shape;
  switch (a.kind) {
    case ShapeKind::kSphere:
      return b.a;
    case ShapeKind::kSphylinder:
    case ShapeKind::kConeSphere: {
      const float t = a.length > 0.0f
                          ? std::clamp(glm::dot(closest - a.a, a.axis) / a.length, 0.0f, 1.0f)
                          : 0.0f;
      return b.a + t * (b.b - b.a);
    }
    case ShapeKind::kOffsetPolygon: {
      const glm::vec3 d = closest - a.a;
      return b.a + glm::dot(d, a.u) * b.u + glm::dot(d, a.v) * b.v;
    }
  }
  return closest;
}

float contactArea(float d, float rr, float* slope) {
  const float pi = std::numbers::pi_v<float>;
  if (d < rr) {
    *slope = 2.0f * pi * (rr - d);
    return pi * d * (2.0f * rr - d);
  }
  *slope = 0.0f;
  return pi * rr * rr;
}

// Contact force magnitude (N) at the touch's depth d: pressure k d (plus k_core (d - d_core)
// past the core) over the disc area pi d (2 rr - d) (pi rr^2 beyond d = rr); and its
// derivative in d.
float contactForce(const Touch& t, float k, float k_core, float* slope) {
  float da = 0.0f;
  const float area = contactArea(t.depth, t.reduced_radius, &da);
  float pressure = k * t.depth;
  float dp = k;
  if (t.depth > t.core_depth) {
    pressure += k_core * (t.depth - t.core_depth);
    dp += k_core;
  }
  *slope = dp * area + pressure * da;
  return pressure * area;
}

// Why a ball state is invalid, or null.
const char* ballProblem(const BallState& b) {
  const auto finite3 = [](const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
  };
  if (!finite3(b.position)) return "position is not finite";
  if (!finite3(b.velocity)) return "velocity is not finite";
  if (!(b.radius > 0.0f) || !std::isfinite(b.radius)) return "radius must be positive and finite";
  if (!(b.mass > 0.0f) || !std::isfinite(b.mass)) return "mass must be positive and finite";
  if (!(b.restitution >= 0.0f && b.restitution <= 1.0f)) return "restitution must be in [0, 1]";
  if (!(b.stiffness > 0.0f)) return "stiffness must be positive (infinity: rigid)";
  return nullptr;
}

struct ContactTable {
  BallStepReport* report = nullptr;
  BallContact* find(int body, int prim) {
    for (int i = 0; i < report->contact_count; ++i) {
      BallContact& c = report->contacts[static_cast<std::size_t>(i)];
      if (c.body == body && c.prim == prim) return &c;
    }
    if (report->contact_count == kMaxBallContacts) {
      ++report->dropped_contacts;
      return nullptr;
    }
    BallContact& c = report->contacts[static_cast<std::size_t>(report->contact_count++)];
    c = BallContact{};
    c.body = body;
    c.prim = prim;
    return &c;
  }
};

}  // namespace

Status validateBallState(const BallState& b) {
  if (const char* why = ballProblem(b)) return fail("ball: {}", why);
  return {};
}

glm::mat4 ballPlacement(const BallState& ball) {
  return glm::translate(glm::mat4(1.0f), ball.position);
}

BallStepReport stepBall(BallState& ball, std::span<const BodyView> bodies, float dt,
                        const BallStepOptions& opt) {
  BallStepReport report;
  if (ballProblem(ball) != nullptr || !(dt > 0.0f) || !(dt <= 1.0f) || !(opt.max_travel > 0.0f) ||
      !(opt.stability > 0.0f) || opt.max_substeps < 1 || !(opt.max_stiffness > 0.0f) ||
      !(opt.core_fraction >= 0.0f && opt.core_fraction <= 1.0f)) {
    return report;
  }
  report.valid = true;
  ContactTable table{&report};
  const bool moving_bodies = opt.previous.size() == bodies.size() && opt.previous_interval > 0.0f;
  const float inv_interval = moving_bodies ? 1.0f / opt.previous_interval : 0.0f;
  const float r = ball.radius;
  const float e2 = ball.restitution * ball.restitution;
  const float k_core = seriesStiffness(ball.stiffness, kRigidStiffness, opt.max_stiffness);
  glm::vec3 impulse(0.0f);
  float remaining = dt;

  // The force on the ball from one touch, accumulated into the table; returns the
  // touch's stiffness slope for the substep size.
  const auto apply = [&](int body, int prim, const Touch& t, float k, const glm::vec3& v_surface,
                         glm::vec3& force, float h, bool record) {
    float slope = 0.0f;
    float f = contactForce(t, k, k_core, &slope);
    if (glm::dot(ball.velocity - v_surface, t.normal) > 0.0f) f *= e2;  // separating
    const glm::vec3 fv = f * t.normal;
    force += fv;
    if (record) {
      BallContact* c = table.find(body, prim);
      if (c != nullptr) {
        c->force += fv * h;  // impulse for now, divided by dt at the end
        c->normal = t.normal;
        c->point = ball.position - r * t.normal;
        c->max_depth = std::max(c->max_depth, t.depth);
        float unused = 0.0f;
        c->area = contactArea(t.depth, t.reduced_radius, &unused);
      }
    }
    return slope;
  };

  // Sum of the contact forces at the current state; `h` > 0 records them as this substep's.
  const auto forces = [&](float h, bool record, float& stiffness_sum) {
    glm::vec3 force(0.0f);
    stiffness_sum = 0.0f;
    if (opt.floor) {
      Touch t;
      t.depth = r - (ball.position.y - opt.floor_height);
      if (t.depth > 0.0f) {
        t.normal = glm::vec3(0.0f, 1.0f, 0.0f);
        t.reduced_radius = r;
        const float k = seriesStiffness(ball.stiffness, opt.floor_stiffness, opt.max_stiffness);
        stiffness_sum += apply(kFloorBody, -1, t, k, glm::vec3(0.0f), force, h, record);
      }
    }
    for (std::size_t bi = 0; bi < bodies.size(); ++bi) {
      const PosedPrimitives* posed = bodies[bi].posed;
      if (posed == nullptr || static_cast<int>(bi) == opt.skip_body) continue;
      const Bounds& bb = posed->bounds;
      const glm::vec3& c = ball.position;
      if (c.x < bb.min.x - r || c.x > bb.max.x + r || c.y < bb.min.y - r || c.y > bb.max.y + r ||
          c.z < bb.min.z - r || c.z > bb.max.z + r) {
        continue;
      }
      const PosedPrimitives* before = moving_bodies ? opt.previous[bi].posed : nullptr;
      if (before != nullptr && before->items.size() != posed->items.size()) before = nullptr;
      for (std::size_t pi = 0; pi < posed->items.size(); ++pi) {
        const PosedPrimitive& p = posed->items[pi];
        Touch t;
        if (!touchPrimitive(p, c, r, opt.core_fraction, t)) continue;
        glm::vec3 v_surface(0.0f);
        if (before != nullptr) {
          v_surface = (t.closest - earlierPoint(p, before->items[pi], t.closest)) * inv_interval;
        }
        const float k = seriesStiffness(ball.stiffness, p.stiffness, opt.max_stiffness);
        stiffness_sum +=
            apply(static_cast<int>(bi), static_cast<int>(pi), t, k, v_surface, force, h, record);
      }
    }
    return force;
  };

  while (remaining > 0.0f) {
    // Substep: bounded travel, and a fraction of the contact's period.
    float stiffness_sum = 0.0f;
    forces(0.0f, false, stiffness_sum);
    float h = remaining;
    const float speed = glm::length(ball.velocity);
    if (speed * h > opt.max_travel) h = opt.max_travel / speed;
    if (stiffness_sum > 0.0f) {
      const float omega = std::sqrt(stiffness_sum / ball.mass);
      h = std::min(h, opt.stability / omega);
    }
    if (report.substeps + 1 >= opt.max_substeps && h < remaining) {
      h = remaining;
      report.saturated = true;
    }
    if (remaining - h < 1e-6f * dt) h = remaining;  // no sliver of a last substep
    const glm::vec3 force = forces(h, true, stiffness_sum);
    ball.velocity += h * (opt.gravity + force / ball.mass);
    ball.position += h * ball.velocity;
    impulse += h * force;
    remaining -= h;
    ++report.substeps;
  }
  // Mean forces over the step, contacts in a fixed order.
  const float inv_dt = 1.0f / dt;
  report.total_force = impulse * inv_dt;
  for (int i = 0; i < report.contact_count; ++i)
    report.contacts[static_cast<std::size_t>(i)].force *= inv_dt;
  std::sort(report.contacts.begin(), report.contacts.begin() + report.contact_count,
            [](const BallContact& x, const BallContact& y) {
              return x.body != y.body ? x.body < y.body : x.prim < y.prim;
            });
  return report;
}

Result<PrimitiveSet> makeBallPrimitives(const BallSpec& s) {
  if (!(s.radius > 0.0f) || !std::isfinite(s.radius) || !(s.reach > 1.0f) ||
      !std::isfinite(s.reach) || !(s.stiffness > 0.0f) || !(s.time_constant > 0.0f) ||
      s.subdivisions < 0 || s.subdivisions > 6) {
    return fail(
        "ball: parameters out of range (radius {}, reach {}, stiffness {}, tau {}, "
        "subdivisions {})",
        s.radius, s.reach, s.stiffness, s.time_constant, s.subdivisions);
  }
  PrimitiveSet set;
  Primitive p;
  p.name = "ball";
  p.role = PrimitiveRole::kLimb;
  p.bone = 0;
  p.shape.kind = ShapeKind::kSphere;
  prepareShape(p.shape);
  p.r_in = s.radius;
  p.r_out = s.radius * s.reach;
  p.weight = shapeWeight(p.density, set.iso, p.r_in, p.r_out);
  p.stiffness = s.stiffness;
  p.elasticity = s.elasticity;
  p.time_constant = s.time_constant;
  set.items.push_back(p);
  return set;
}

Result<BallBody> makeBall(const BallSpec& s) {
  Result<PrimitiveSet> set = makeBallPrimitives(s);
  if (!set) return set.error();
  BallBody b;
  b.skeleton.names = {"ball"};
  b.skeleton.parents = {kNoParent};
  b.skeleton.rest_local.resize(1);
  computeInverseBind(b.skeleton);
  icosphere(s.radius, s.subdivisions, b.mesh);
  b.model.primitives = std::move(*set);
  finalizeGraph(b.model.graph, 1);
  const std::size_t nv = b.mesh.positions.size();
  b.model.calibration.vertex_class.assign(nv, VertexClass::kLimb);
  b.model.calibration.prims.assign(nv, {0, kNoPrimitive, kNoPrimitive, kNoPrimitive});
  b.model.calibration.rigid.assign(nv, 1);
  computeRelaxationWeights(b.mesh.positions, b.mesh.normals, b.mesh.indices, b.model.calibration);
  Result<CalibrationReport> rep = calibrateModel(b.model, b.mesh.positions, b.mesh.normals);
  if (!rep) return rep.error();
  return b;
}

}  // namespace vistel
