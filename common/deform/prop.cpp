#include "common/deform/prop.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>

#include "common/deform/calibrate.hpp"
#include "common/deform/collision_terms.hpp"
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

// An overlap between the ball and a skin: its volume (m^3) and the area (m^2) of the surface
// where they cross, projected on the contact's normal (dV/dd).
struct Overlap {
  float volume = 0.0f;
  float area = 0.0f;
};
Overlap overlap(float d, float r, float rs);  // the lens of two spheres (below)

// The quadrature of the ball's cap (capIntegral): kIntegralRings rings of kCapAzimuths points.
constexpr int kIntegralRings = 8;
constexpr int kCapAzimuths = 16;
struct CapSamples {
  std::array<float, kIntegralRings * kCapAzimuths> depth{};  // below the skin, m (> 0: inside)
  std::array<float, kIntegralRings> element{};  // a point's area element, projected (m^2)
};

// One sampled contact of the ball's surface with a surface of local radius r_s.
struct Touch {
  float depth = 0.0f;
  glm::vec3 normal{0.0f, 1.0f, 0.0f};  // from the surface towards the ball
  glm::vec3 closest{0.0f};             // nearest point of the primitive's skeleton
  float surface_radius = INFINITY;     // r_s, the skin's local radius (infinity: a plane)
  float skin_radius = 0.0f;            // the skin's distance from the skeleton (m)
  float body_core = INFINITY;          // depths where the body's core and the ball's begin
  float ball_core = INFINITY;          // (contactCoreDepth), m
  bool integrated = false;             // `cap` holds the cap's samples (capIntegral); else
  CapSamples cap;                      // the lens of the ball and the r_s sphere
};

// Directions of the ball's lower cap sampled by capDepth: rings at these angles from the
// point nearest the primitive's skeleton, kCapAzimuths points each.
constexpr float kCapAngles[] = {0.1396f, 0.2793f, 0.4189f, 0.5585f, 0.6981f, 0.8378f};  // 8..48 deg

// How deep point q lies inside the primitive's skin, along its own ray from the skeleton
// (metres; negative: outside).
float skinDepth(const PosedPrimitive& p, const glm::vec3& q) {
  float sc;
  const glm::vec3 d = skeletonOffset(p.shape, q, sc);
  // Skeleton units to metres: 1 for metric shapes, the local radius for cone-spheres.
  const float units = sc > 0.0f ? 1.0f / sc : 1.0f;
  const float w = skinWeight(p, q, d, sc);
  return skinSurfaceDistance(p, w) * units - std::sqrt(glm::dot(d, d));
}

// The common pressure law's integral over the ball's cap facing the skeleton (direction
// -normal), by quadrature: the sum over the cap's points inside the skin of their depth
// (skinDepth) times the cap's area element, projected on the normal, i.e. the overlap volume
// V, so that F = k V (prop.hpp); `area` gets the projected area of the points inside, dV/dd.
// Midpoint rule on kIntegralRings rings of kCapAzimuths points from the ball's pole to
// theta_max (radians), which should enclose the contact with some margin.
void capIntegral(const PosedPrimitive& p, const glm::vec3& c, float r, const glm::vec3& normal,
                 float theta_max, CapSamples& out) {
  const glm::vec3 helper =
      std::abs(normal.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  const glm::vec3 e1 = glm::normalize(glm::cross(normal, helper));
  const glm::vec3 e2 = glm::cross(normal, e1);
  const float pi = std::numbers::pi_v<float>;
  const float d_theta = theta_max / kIntegralRings;
  const float d_phi = 2.0f * pi / kCapAzimuths;
  for (int j = 0; j < kIntegralRings; ++j) {
    const float theta = (static_cast<float>(j) + 0.5f) * d_theta;
    const float ct = std::cos(theta), st = std::sin(theta);
    // Projected on the normal: the ring's surface element r^2 sin dtheta dphi times cos.
    out.element[static_cast<std::size_t>(j)] = r * r * st * ct * d_theta * d_phi;
    for (int k = 0; k < kCapAzimuths; ++k) {
      const float b = (static_cast<float>(k) + 0.5f * static_cast<float>(j & 1)) * d_phi;
      const glm::vec3 q = c + r * (-ct * normal + st * (std::cos(b) * e1 + std::sin(b) * e2));
      out.depth[static_cast<std::size_t>(j * kCapAzimuths + k)] = skinDepth(p, q);
    }
  }
}

// The overlap the cap's samples measure past `offset` (m) of depth: the sum of each inside
// point's depth beyond it times its area element (volume), and of those elements (area).
Overlap capOverlap(const CapSamples& cap, float offset) {
  Overlap o;
  for (int j = 0; j < kIntegralRings; ++j) {
    const float element = cap.element[static_cast<std::size_t>(j)];
    for (int i = j * kCapAzimuths; i < (j + 1) * kCapAzimuths; ++i) {
      const float d = cap.depth[static_cast<std::size_t>(i)] - offset;
      if (!(d > 0.0f)) continue;
      o.volume += d * element;
      o.area += element;
    }
  }
  return o;
}

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
      deepest = std::max(deepest, skinDepth(p, q));
    }
  }
  return deepest;
}

// Contact of the ball (centre c, radius r) with one posed primitive's skin: its iso-surface
// w_i F_i = T, w_i the calibrated skin weight (the bare F_i = T without one).
bool touchPrimitive(const PosedPrimitive& p, const glm::vec3& c, float r, Touch& t) {
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
  const bool skinned = p.skin_weight != nullptr && dist - r < p.reach;
  if (skinned) depth = std::max(depth, capDepth(p, c, r, normal));
  if (!(depth > 0.0f)) return false;
  // The skin's overlap with the ball by quadrature over the cap (the skin is no sphere),
  // out to 1.5 times the angle where the lens of the r_s sphere ends, at least 20 degrees.
  if (skinned) {
    const Overlap lens = overlap(depth, r, r_s);
    const float a = std::sqrt(std::max(lens.area, 0.0f) / std::numbers::pi_v<float>);
    const float theta = std::asin(std::min(a / r, 1.0f));
    capIntegral(p, c, r, normal,
                std::min(std::max(1.5f * theta, 0.35f), 0.5f * std::numbers::pi_v<float>), t.cap);
    t.integrated = true;
  }
  t.depth = depth;
  t.normal = normal;
  t.closest = c - dist * t.normal;
  t.surface_radius = p.shape.kind == ShapeKind::kOffsetPolygon ? INFINITY : r_s;
  t.skin_radius = r_s;
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

// Where a body reaches its core (contactCoreDepth) with a core fraction of its own.
float coreDepthAt(float core_fraction, float skin_radius, float k_own, float k_other) {
  const float share = shareOf(k_own, k_other);
  return share > 0.0f ? (1.0f - core_fraction) * skin_radius / share : INFINITY;
}

// The overlap of the ball (radius r) with the skin's local sphere (radius rs; infinity: a
// plane) at interpenetration depth d (centres r + rs - d apart): its volume (m^3) and the area
// of its disc, where the two surfaces cross (m^2), which is also dV/dd. Closed forms: the
// spherical cap pi d^2 (3 r - d) / 3 against a plane; the lens
// pi (r + rs - D)^2 (D^2 + 2 D (r + rs) - 3 (r - rs)^2) / (12 D) between spheres, D the
// centres' distance, and the disc's radius a^2 = (4 D^2 r^2 - (D^2 - rs^2 + r^2)^2) / (4 D^2).
// For d << the radii both tend to V = pi R* d^2, A = 2 pi R* d, R* = r rs / (r + rs).
Overlap overlap(float d, float r, float rs) {
  const double pi = std::numbers::pi;
  Overlap o;
  if (!(d > 0.0f)) return o;
  const double dd = d, R = r;
  if (!std::isfinite(rs)) {
    const double h = std::min(dd, 2.0 * R);
    o.volume = static_cast<float>(pi * h * h * (3.0 * R - h) / 3.0);
    o.area = h < 2.0 * R ? static_cast<float>(pi * h * (2.0 * R - h)) : 0.0f;
    return o;
  }
  const double S = rs;
  const double D = R + S - dd;
  if (D <= std::abs(R - S)) {  // one inside the other
    const double m = std::min(R, S);
    o.volume = static_cast<float>(4.0 / 3.0 * pi * m * m * m);
    return o;
  }
  const double gap = R + S - D;  // = d
  o.volume = static_cast<float>(pi * gap * gap *
                                (D * D + 2.0 * D * (R + S) - 3.0 * (R - S) * (R - S)) / (12.0 * D));
  const double x = D * D - S * S + R * R;
  o.area = static_cast<float>(std::max(0.0, pi * (4.0 * D * D * R * R - x * x) / (4.0 * D * D)));
  return o;
}

// Contact force magnitude (N) at the touch's depth d, the common pressure law integrated over
// the contact (see prop.hpp): k V, V the overlap (the cap's quadrature, or the lens), plus
// k_core V_core past each core (the body's with k_core = the ball's stiffness against a rigid
// body, the ball's with the body's); and its derivative in d (k A + ...), for the substeps.
// `area` gets the contact's projected area.
float contactForce(const Touch& t, float k, float k_body_core, float k_ball_core, float r,
                   float core_fraction, float* slope, float* area) {
  // Point by point over the cap, as Step 3 on a mesh (capOverlap), or the lens.
  const Overlap o = t.integrated ? capOverlap(t.cap, 0.0f) : overlap(t.depth, r, t.surface_radius);
  float f = k * o.volume;
  float df = k * o.area;
  // The cores: past each, a second layer as stiff as the other body against a rigid one.
  // Each core is a sphere of core_fraction times its body's radius meeting the other body's
  // skin by the same law (a lens); the body's also on the cap's points, the larger of the two
  // (the cap's points cannot see a part the ball has swallowed, a hand).
  struct Core {
    float depth, k, r_ball, r_body;
    bool cap;
  };
  for (const Core& core :
       {Core{t.body_core, k_body_core, r, core_fraction * t.surface_radius, true},
        Core{t.ball_core, k_ball_core, core_fraction * r, t.surface_radius, false}}) {
    if (!(t.depth > core.depth)) continue;
    Overlap c = overlap(t.depth - core.depth, core.r_ball, core.r_body);
    if (t.integrated && core.cap) {
      const Overlap q = capOverlap(t.cap, core.depth);
      if (q.volume > c.volume) c = q;
    }
    f += core.k * c.volume;
    df += core.k * c.area;
  }
  *slope = df;
  *area = o.area;
  return f;
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

float contactCoreDepth(float skin_radius, float k_own, float k_other) {
  return coreDepthAt(kCoreFraction, skin_radius, k_own, k_other);
}

float contactCorePressure(float depth, float pressure, float k_own, float own_radius,
                          float partner_radius) {
  if (!(depth > 0.0f) || !(pressure > 0.0f) || !std::isfinite(pressure) || !(k_own > 0.0f)) {
    return 0.0f;
  }
  // The series stiffness k and the body's share s of the depth (shareOf): k = k_own s for a
  // soft body, so s = k / k_own and the partner's stiffness k_other = k / (1 - s), rigid
  // where s reaches 1; a rigid body takes no share (s = 0) and k = k_other.
  const float k = pressure / depth;
  float share = 0.0f;
  float k_other = k;
  if (!std::isinf(k_own)) {
    share = std::min(k / k_own, 1.0f);
    k_other = share > 0.999f ? kRigidStiffness : k / (1.0f - share);
  }
  float extra = 0.0f;
  // The body's own core, stiffened by the partner's stiffness against a rigid one.
  if (own_radius > 0.0f && share > 0.0f) {
    const float core = (1.0f - kCoreFraction) * own_radius / share;
    if (depth > core) extra += std::min(k_other, kMaxContactStiffness) * (depth - core);
  }
  // The partner's, stiffened by this body's.
  if (partner_radius > 0.0f && share < 1.0f) {
    const float core = (1.0f - kCoreFraction) * partner_radius / (1.0f - share);
    if (depth > core) extra += std::min(k_own, kMaxContactStiffness) * (depth - core);
  }
  return extra;
}

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
  const float k_body_core = seriesStiffness(ball.stiffness, kRigidStiffness, opt.max_stiffness);
  glm::vec3 impulse(0.0f);
  float remaining = dt;

  // The force on the ball from one touch, accumulated into the table; returns the
  // touch's stiffness slope for the substep size.
  const auto apply = [&](int body, int prim, Touch& t, float k_body, const glm::vec3& v_surface,
                         glm::vec3& force, float h, bool record) {
    const float k = seriesStiffness(ball.stiffness, k_body, opt.max_stiffness);
    t.body_core = coreDepthAt(opt.core_fraction, t.skin_radius, k_body, ball.stiffness);
    t.ball_core = coreDepthAt(opt.core_fraction, r, ball.stiffness, k_body);
    const float k_ball_core = seriesStiffness(k_body, kRigidStiffness, opt.max_stiffness);
    float slope = 0.0f;
    float area = 0.0f;
    float f = contactForce(t, k, k_body_core, k_ball_core, r, opt.core_fraction, &slope, &area);
    f *= restitutionScale(ball.restitution, glm::dot(ball.velocity - v_surface, t.normal));
    const glm::vec3 fv = f * t.normal;
    force += fv;
    if (record) {
      BallContact* c = table.find(body, prim);
      if (c != nullptr) {
        c->force += fv * h;  // impulse for now, divided by dt at the end
        c->normal = t.normal;
        c->point = ball.position - r * t.normal;
        c->max_depth = std::max(c->max_depth, t.depth);
        c->area = area;
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
        t.skin_radius = INFINITY;  // no core under the floor
        stiffness_sum +=
            apply(kFloorBody, -1, t, opt.floor_stiffness, glm::vec3(0.0f), force, h, record);
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
        if (!touchPrimitive(p, c, r, t)) continue;
        glm::vec3 v_surface(0.0f);
        if (before != nullptr) {
          v_surface = (t.closest - earlierPoint(p, before->items[pi], t.closest)) * inv_interval;
        }
        stiffness_sum += apply(static_cast<int>(bi), static_cast<int>(pi), t, p.stiffness,
                               v_surface, force, h, record);
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
