// Props: bodies with their own primitives and (optionally) a skin, e.g. a ball
// (DESIGN.md §3 "Props", §6). A ball is one sphere primitive on a one-joint skeleton whose
// only transform is the ball's placement; soft or rigid, with an elasticity over time.
//
// Ball dynamics (stepBall) use primitives only, no meshes, so a server that has just
// skeletons, primitive sets and postures can step props: each posed primitive's surface is
// its skin, w_i F_i = T with w_i its calibrated skin weight (skinSurfaceDistance: the bare
// iso-surface at r_in without one).
//
// The contact law, one model for the ball dynamics and for the forces Step 3 measures on the
// deformed meshes (contact_forces.cpp), after Gascuel 1993's reaction pressure:
//   pressure p(x) = k delta(x) + [cores],  force F = integral of p over the contact,
// where delta(x) (m) is the rigid-pose interpenetration at a point of the contact: how deep
// that point of one body's skin lies below the other's skin, measured on the other
// primitive's ray through it (skinSurfaceDistance - skeleton distance); k (Pa/m) the two
// materials' stiffnesses in series (k_a k_b / (k_a + k_b); a rigid side yields nothing, rigid
// on rigid kMaxContactStiffness); the integral over the skinned (rigid-pose) contact surface,
// so F (N) = k x the overlap volume (m^3) for a Winkler foundation. Cores: each body has a
// rigid core (a bone; a ball's centre) at kCoreFraction of its skin's distance from its
// skeleton; it takes its share of delta (relative deformability, shareOf), so it reaches its
// core at delta_c = (1 - kCoreFraction) r / share (contactCoreDepth), and past it the pressure
// gains k_core (delta - delta_c), k_core the other body's stiffness against a rigid one (at
// most kMaxContactStiffness), so fast balls do not pass through.
//   The dynamics integrate it over the ball's cap facing the primitive's skeleton: depths at
// 8 rings x 16 points of the cap (each on its own ray) times their area elements projected on
// the contact normal (a midpoint rule out to 1.5 times the contact's angle), so the skin's
// real shape counts, not a sphere; the cores' layers by the lens of the core's sphere and the
// other skin (the larger of lens and quadrature for the body's core, as the cap cannot see a
// part the ball has swallowed, a hand). The normal is the field's gradient direction at the
// ball's centre; the contact's depth (for detection, max_depth and the cores) the deepest
// of the centre's ray and 96 cap points (8..48 degrees).
//   Step 3 sums the same law over the mesh: each contact vertex's pressure from its depth
// below the partner's skin on the partner primitive's ray (exact for every profile) plus the
// cores', linear over each face around the contact (zero at vertices not in contact), times
// the face's skinned area, along the deformed face normal.
// Measured on a ball bouncing on the default avatar's head and thigh (tests/deform/
// bounce_force_test.cpp) the two agree within 10% per frame and 2% in impulse.
// Restitution e: the force is scaled by e^2 while the ball separates from the surface
// (relative normal velocity outward: restitutionScale), so a bounce returns e^2 of the
// energy stored, i.e. leaves at e times the impact speed. Step 3 does the same per body pair
// (separationScale) from the bodies' velocities and restitutions in their BodyViews (e = the
// product of the two; a prop's velocity is its dynamics' own, an avatar's is taken as 0).
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include <glm/glm.hpp>

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"
#include "common/deform/interactions.hpp"

namespace vistel {

struct BallSpec {
  float radius = 0.1f;                // metres (> 0)
  float stiffness = kRigidStiffness;  // Pa per metre; kRigidStiffness = rigid
  Elasticity elasticity = Elasticity::kElastic;
  float time_constant = 0.5f;  // viscoelastic recovery, seconds
  float reach = 1.5f;          // field support radius / radius (> 1)
  int subdivisions = 3;        // icosphere levels (0..6): 20 * 4^s triangles
};

struct BallBody {
  Skeleton skeleton;    // one joint "ball" at the origin
  SkinMesh mesh;        // icosphere of the given radius about the origin
  ImplicitModel model;  // one sphere primitive, calibrated on the mesh
};

// Builds a ball body; fails on out-of-range parameters. Cost: O(mesh), at load time.
Result<BallBody> makeBall(const BallSpec& spec);

// Only the primitive part (for a server, which needs no mesh): a PrimitiveSet with the
// sphere and an empty CombinationGraph.
Result<PrimitiveSet> makeBallPrimitives(const BallSpec& spec);

// --- Ball dynamics from primitives ------------------------------------------------------

// The state a server keeps (and sends in snapshots) per ball. World space: metres, +Y up,
// seconds, kilograms.
struct BallState {
  glm::vec3 position{0.0f};           // centre
  glm::vec3 velocity{0.0f};           // m/s
  float radius = 0.1f;                // m (> 0)
  float mass = 0.4f;                  // kg (> 0)
  float restitution = 0.7f;           // e in [0, 1]: rebound speed / impact speed
  float stiffness = kRigidStiffness;  // the ball's own, Pa per metre of depth (> 0);
                                      // kRigidStiffness = rigid (the partner yields)
};

// Checks finite fields and the ranges above. The message names the field.
Status validateBallState(const BallState& ball);

// The ball's placement (a translation) for posing its PrimitiveSet (makeBallPrimitives with
// the same radius) as a body of Step 1: posePrimitives(set, {&placement, 1}, posed).
glm::mat4 ballPlacement(const BallState& ball);

// --- The contact law, shared by the ball dynamics and Step 3's mesh forces ---------------

// A body's rigid core (a bone; a ball's centre): the inner kCoreFraction of its skin's
// distance from its skeleton. Past it the contact stiffens by the partner's stiffness against
// a rigid body, at most kMaxContactStiffness (which also caps rigid on rigid).
inline constexpr float kCoreFraction = 0.5f;
inline constexpr float kMaxContactStiffness = 1.0e7f;

// The interpenetration depth (m) at which a body of stiffness k_own (Pa/m), whose skin lies
// skin_radius m from its skeleton, reaches its core against a partner of stiffness k_other:
// its own dent is its share of the depth (shareOf, relative deformability), so the core is
// at (1 - kCoreFraction) skin_radius / share. Infinity for a rigid body (it takes no dent).
float contactCoreDepth(float skin_radius, float k_own, float k_other);

// The cores' extra pressure (Pa) at a mesh vertex of a body of stiffness k_own penetrating its
// partner `depth` m in the rigid pose with the common law's pressure `pressure` = k depth (k
// the series stiffness, from which the partner's stiffness is recovered); its skin lies
// own_radius m from its skeleton, the partner's partner_radius m from the partner's (on the
// same ray; 0: unknown, no core): past each body's core (contactCoreDepth) k_core (depth -
// core depth), k_core the other body's stiffness against a rigid one, at most
// kMaxContactStiffness. 0 before the cores and for bad input. Cost: a few operations.
float contactCorePressure(float depth, float pressure, float k_own, float own_radius,
                          float partner_radius);

// The restitution factor of the contact law at a relative normal velocity v_n (m/s; > 0:
// separating): e^2 while separating, else 1.
inline float restitutionScale(float e, float v_n) { return v_n > 0.0f ? e * e : 1.0f; }

// The same for a body pair in Step 3 (e = e_body e_partner): v_n is the partner's velocity
// relative to the body along `push`, the direction the contact pushes the partner.
inline float separationScale(float e_body, float e_partner, const glm::vec3& v_body,
                             const glm::vec3& v_partner, const glm::dvec3& push) {
  const float e = e_body * e_partner;
  const double len = glm::length(push);
  if (!(e < 1.0f) || !(len > 0.0)) return 1.0f;
  const double v_n = glm::dot(glm::dvec3(v_partner) - glm::dvec3(v_body), push) / len;
  return restitutionScale(e, static_cast<float>(v_n));
}

struct BallStepOptions {
  // m/s^2
  glm::vec3 gravity{0.0f, -9.81f, 0.0f};
  // A rigid floor plane at y = floor_height (m), of floor_stiffness (Pa/m).
  bool floor = true;
  float floor_height = 0.0f;
  float floor_stiffness = kRigidStiffness;
  // Cap on the series stiffness (rigid on rigid), Pa/m; also the stiffness of a
  // primitive's rigid core: its inner core_fraction of the surface radius (a bone).
  float max_stiffness = kMaxContactStiffness;
  float core_fraction = kCoreFraction;
  // Substeps move the ball at most max_travel (m), last at most stability / omega of the
  // current contact (omega^2 = contact stiffness slope / mass), and number at most
  // max_substeps per call (beyond, the last substep takes the rest: report.saturated).
  float max_travel = 0.01f;
  float stability = 0.2f;
  int max_substeps = 256;
  // A body index to ignore (the ball's own body, if it is listed among the bodies).
  int skip_body = -1;
  // Optional: the same bodies posed previous_interval seconds earlier (same sizes), for
  // the velocity of the touching surface (a hand hitting the ball). Empty: bodies still.
  std::span<const BodyView> previous{};
  float previous_interval = 0.0f;
};

// One (body, primitive) the ball touched during a step; the body feels -force.
struct BallContact {
  int body = -1;           // index into `bodies`; kFloorBody for the floor
  int prim = -1;           // primitive index in that body (-1 for the floor)
  glm::vec3 force{0.0f};   // N on the ball, mean over the step (impulse / dt)
  glm::vec3 normal{0.0f};  // unit, from the surface towards the ball (last substep)
  glm::vec3 point{0.0f};   // contact point on the ball's surface (last substep), world
  float max_depth = 0.0f;  // deepest penetration during the step (m)
  float area = 0.0f;       // contact area at the last substep in contact, projected on
                           // the normal (m^2)
};

inline constexpr int kMaxBallContacts = 16;
inline constexpr int kFloorBody = -2;

struct BallStepReport {
  bool valid = false;  // false: the state or dt was invalid, nothing moved
  int substeps = 0;
  bool saturated = false;  // max_substeps reached (the last substep was longer)
  int contact_count = 0;   // entries of contacts, sorted by (body, prim), floor first
  std::array<BallContact, kMaxBallContacts> contacts{};
  int dropped_contacts = 0;     // distinct contacts beyond kMaxBallContacts (their force is
                                // still applied and in total_force)
  glm::vec3 total_force{0.0f};  // N on the ball from all contacts, mean over the step
};

// Advances `ball` by dt seconds (0 < dt <= 1) under gravity, the floor and the contact
// reaction of every posed primitive of `bodies` that takes part in collisions (bodies with
// a null posed set, and skip_body, are ignored). Semi-implicit Euler over adaptive
// substeps (at most max_travel of motion each, and short against the contact's own
// period), so results depend only on the inputs: deterministic, no allocation, cost
// O(substeps * primitives near the ball), each touching primitive about 2 x 224 skin-surface
// evaluations (the cap's depth and quadrature) per substep. The body's posture is taken as constant
// over dt (its surface velocity from options.previous when given).
BallStepReport stepBall(BallState& ball, std::span<const BodyView> bodies, float dt,
                        const BallStepOptions& options = {});

}  // namespace vistel
