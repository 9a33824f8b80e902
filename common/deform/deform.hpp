// Steps 2 and 3 of the deformable component (DESIGN.md §3), run per body per frame after
// the rigid component (skinning):
//   Step 2: every skin vertex moves from its rigidly posed position P along its rigidly
//     posed normal n (or along -grad F where they disagree, or along the contact surface's
//     normal where the root along n lies far beyond the vertex's penetration) to P' on
//     F = T, where
//       F(P) = w_v D_v(P) + sum_i COLL_i,v(P)
//     over the primitives i that Step 1 found touching v's primitives (other bodies, or
//     non-blending parts of the same body); Gascuel 1993 "An implicit formulation for
//     precise contact modeling between flexible solids" for the penetration and
//     propagation zones, with relative deformability and elastic memory (plastic,
//     viscoelastic). A vertex inside a rigid partner (a hard constraint) retreats onto its
//     surface; where the partner is a sphere, sphylinder or cone-sphere with Wyvill's profile
//     its inside is convex and the point where a line leaves it comes in closed form, else
//     from a line search. A joint vertex whose root lies beyond its own side (where DIFF is the
//     opposite limb's field alone; see DeformOptions::joint_own_side) stays at P: a
//     deliberate departure from DESIGN.md, whose equation degenerates there. Then a
//     tangential relaxation of the moved joint vertices towards their rest barycentric
//     positions and a final projection (Vaillant et al. 2013, "Implicit skinning:
//     real-time skin deformation with contact modeling").
//     Last, the corrections c = P' - P of the joint regions are smoothed over the mesh
//     (DeformOptions::smooth_passes): every joint vertex has its own calibration weight
//     w_v, so its own iso-surface, and where the skinning slides a joint region across its
//     primitives (a raised shoulder) neighbours with weights from 0.25 to 1.3 would follow
//     surfaces centimetres apart and crumple the skin. Joint vertices, and free vertices
//     beside them, move towards their one-ring's mean correction unless a collision term
//     shaped their solution (touching, penetrating in the rigid pose, or near another body,
//     which may bulge them): those keep it. At rest every correction is 0 and nothing moves.
//     Also a departure from DESIGN.md, which leaves each vertex on its own surface.
//     Last of all, a guard: a face turned inside out against the skinned skin outside
//     contacts has its vertices' corrections pulled back until it is not
//     (face_orientation.hpp).
//   Step 3: normals of the deformed skin, contact flags and areas, pressures and reaction
//     forces per partner body.
// The code follows these steps: deform.cpp the driver (deformSkin: setup, pass A, pass B,
// relaxation, smoothing, Step 3, each a call), collision_terms.hpp the paper's terms,
// vertex_solve.* the vertex solve (pass B), penetration_pass.cpp pass A (candidates,
// rigid-pose penetrations, p_max), relaxation.* relaxation and smoothing, contact_forces.*
// Step 3, deform_scratch.* the acceleration machinery's scratch (internal headers).
//
// Space: world (rigid positions, normals and posed primitives must share it), metres,
// seconds. Cost: O(n) in skin vertices; a limb vertex skinned by its primitive's bone alone
// costs no evaluation unless a collider's term can be non-zero within 1 cm (plus its last
// offset) of it (a bound from the skeleton distance, per patch of vertices and then per
// vertex); no heap allocation once the state has seen the scene's largest interaction list.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/deform/collision_terms.hpp"
#include "common/deform/implicit_model.hpp"
#include "common/deform/interactions.hpp"
#include "common/deform/posed_primitives.hpp"
#include "common/deform/root_finding.hpp"
#include "common/deform/task_pool.hpp"

namespace vistel {

enum class ProjectionMode : std::uint8_t {
  kNormal = 0,    // along the rigidly posed vertex normal (switching to -grad F per vertex
                  // where the two disagree, see gradient_switch_cos)
  kGradient = 1,  // along -grad F at the rigid position, for every vertex
};

struct DeformOptions {
  ProjectionMode projection = ProjectionMode::kNormal;
  float gradient_switch_cos = 0.25f;  // use -grad F where cos(n, -grad F) is below this (the
                                      // gradient of the vertex's own side: its joint, own
                                      // limb and bone, without the crease term, whose
                                      // gradient is singular on the crease, nor the opposite
                                      // limb); also used when the normal finds no root
  RootOptions root;                   // tolerances of the per-vertex root-find
  bool collisions = true;             // false: own fields only (creases, bones)
  bool propagation = true;            // false: no bulge (the propagation zone's term is 0)
  bool self_propagation = false;      // bulges for self-contact too (two facing parts of
                                      // one body both bulge into the gap between them)
  float joint_own_side = 0.3f;        // a joint vertex's root must lie where its own side
                                      // (w_v times its joint, own limb and bone fields) keeps
                                      // at least this fraction of its value at the start of
                                      // the projection (at most T); else the vertex is held
                                      // rigid (0: off)
  float own_fade_low = 0.999f;        // the own field's surface fades into the skinned one
  float own_fade_high = 0.999f;       // where the skinning does not follow the bones the
                                      // vertex's own field models (Calibration::own_weight:
                                      // its own primitives' bones and a limb's partner across
                                      // a joint primitive): a vertex they carry with this low
                                      // share of its skin weight or less keeps its skinned
                                      // position as its own surface (w_v D_v is solved for
                                      // its value there; contacts still move it), one with
                                      // the high share or more is drawn to the field's
                                      // (w_v D_v = T), and between the two a linear blend
                                      // (the target shifts by the skinned position's excess
                                      // times the faded share). By default a step: only
                                      // vertices wholly carried by modelled bones take the
                                      // field's surface; own_fade_high = 0: no fade
  int relax_passes = 2;               // tangential relaxation passes (0: off)
  float relax_rate = 0.5f;            // fraction of the way to the rest barycentre per pass
  float relax_min_offset = 1e-3f;     // relax joint vertices that moved more than this (m)
  int smooth_passes = 2;              // passes smoothing the joint regions' corrections
                                      // P' - P (0: off; see the header)
  float smooth_rate = 0.5f;           // fraction of the way to the one-ring's mean
                                      // correction per pass
  float move_margin = 0.005f;         // with DeformInput::rest_positions, no vertex ends
                                      // farther from its skinned position than its drift (how
                                      // far the skinning put it from where its own primitives'
                                      // bones alone carry it: all its own field can correct),
                                      // plus its rigid-pose penetration depth, plus the bulge
                                      // the body's deepest contact allows, plus this (m); a
                                      // root beyond leaves it rigid (held) or, in contact, at
                                      // that distance. Negative: no bound
  int chunk_size = 512;               // vertices per parallel task (results do not depend on it
                                      // nor on the thread count)
  bool time_phases = false;           // measure each phase's wall time (DeformCounters::
                                      // phase_seconds; a clock read between phases)
  bool reference = false;             // the plain scalar way, for tests: every collider of a
                                      // vertex's interaction list tested directly per vertex
                                      // (no patches, no vectorised culling, no field lanes, no
                                      // lone-limb short way, no kept problems); the same
                                      // equations, so the same result up to float rounding
};

struct DeformInput {
  std::span<const glm::vec3> rigid_positions;  // skinned positions (nvert), world
  std::span<const glm::vec3> rigid_normals;    // skinned unit normals (nvert), world
  std::span<const std::uint32_t> indices;      // the skin's triangles (3 * ntri)
  double time = 0.0;                           // seconds; drives viscoelastic recovery
  std::span<const glm::vec3> rest_positions;   // the skin at rest, bind-pose model space
                                               // (nvert; empty: moves are not bounded, see
                                               // DeformOptions::move_margin)
};

// Wall time of each phase of one deformSkin call, seconds (see DeformOptions::time_phases).
struct DeformPhaseTimes {
  double penetration = 0.0;  // the colliders, then pass A: candidates, rigid-pose penetrations
  double solve = 0.0;        // pass B: Step 2's root-finding, vertex by vertex
  double relax = 0.0;        // tangential relaxation
  double smooth = 0.0;       // smoothing the joint regions' corrections, the move bound
                             // and the face orientation guard
  double normals = 0.0;      // Step 3a
  double contacts = 0.0;     // Step 3b: contact areas and forces

  DeformPhaseTimes& operator+=(const DeformPhaseTimes& o) {
    penetration += o.penetration;
    solve += o.solve;
    relax += o.relax;
    smooth += o.smooth;
    normals += o.normals;
    contacts += o.contacts;
    return *this;
  }
};

// Per-frame counters (reset by each deformSkin).
struct DeformCounters {
  std::int64_t evaluations = 0;       // per-vertex function evaluations, all passes (a
                                      // rigid partner's surface found in closed form counts
                                      // as one)
  std::int64_t iterations = 0;        // Step 2 root-finding iterations, before relaxation:
                                      // the evaluations after the first, and a last Newton
                                      // step taken without evaluating (RootOptions::
                                      // final_step); a closed-form retreat onto a rigid
                                      // partner counts as one
  std::int64_t relax_iterations = 0;  // iterations of the relaxation's final projections
  int iterating_vertices = 0;         // vertices whose first evaluation was not a root
  int unsolved_vertices = 0;          // no root within reach: left at the rigid position
  int held_vertices = 0;              // joint vertices whose root left their own side (see
                                      // DeformOptions::joint_own_side): left rigid by the
                                      // solve (the smoothing may move them)
  int gradient_vertices = 0;          // projected along -grad F (normal disagreed)
  int relaxed_vertices = 0;           // moved by tangential relaxation
  int smoothed_vertices = 0;          // moved by the smoothing of corrections
  int reoriented_vertices = 0;        // pulled back so that no face is turned inside out
                                      // outside contacts (face_orientation.hpp)
  int contact_vertices = 0;           // on a contact surface
  int candidate_overflow = 0;         // vertices with more colliders than kMaxCandidates
  int candidate_vertices = 0;         // vertices with at least one collision candidate
  int rigid_vertices = 0;             // rigid limb vertices with nothing near: no evaluation
  float max_offset = 0.0f;            // largest |P' - P| (m)
  DeformPhaseTimes phase_seconds;     // with DeformOptions::time_phases; else zeros

  // Mean iterations over the vertices that iterate (the paper reports 2-3).
  double iterationsPerVertex() const {
    return iterating_vertices > 0 ? static_cast<double>(iterations) / iterating_vertices : 0.0;
  }
};

// Contact of this body with one partner body, from this body's own contact faces.
struct BodyContact {
  int partner = -1;        // body index in the scene (may be this body: self-contact)
  glm::dvec3 force{0.0};   // N on this body: the contact law (prop.hpp) integrated over
                           // every face around the contact, -p_mean * skinned area * n
  double area = 0.0;       // m^2 of faces whose three vertices lie on the contact (each
                           // at most its skinned area: stretched faces count as the skin
                           // that was there)
  glm::dvec3 centre{0.0};  // area-weighted centroid of those faces (world)
  double max_depth = 0.0;  // deepest rigid-pose penetration of a vertex (m)
  int vertices = 0;        // contact vertices
};

inline constexpr std::uint8_t kVertexMoved = 1;       // P' != P
inline constexpr std::uint8_t kVertexUnsolved = 2;    // no root: left rigid
inline constexpr std::uint8_t kVertexGradient = 4;    // projected along -grad F
inline constexpr std::uint8_t kVertexRelaxed = 8;     // moved by relaxation
inline constexpr std::uint8_t kVertexContact = 16;    // on a contact surface
inline constexpr std::uint8_t kVertexReshaped = 32;   // moved enough to need a new normal
inline constexpr std::uint8_t kVertexHeld = 64;       // joint vertex held rigid (see held_vertices)
inline constexpr std::uint8_t kVertexSmoothed = 128;  // moved by the smoothing of corrections
inline constexpr int kMaxCandidates = 8;              // colliders per vertex

struct DeformScratch;  // deform_scratch.hpp (internal)

// Everything that changes per frame for one deformed body, results and carried state; sized
// once by initDeformState. Copyable (the scratch is deep-copied) and movable.
struct DeformState {
  std::vector<glm::vec3> positions;        // deformed positions (nvert), world
  std::vector<glm::vec3> normals;          // deformed unit normals (nvert), world
  std::vector<float> offset;               // last solution along the projection direction (nvert),
                                           // the next frame's warm start (m)
  std::vector<float> free_offset;          // same without collision terms (nvert), plastic and
                                           // viscoelastic vertices only (m)
  std::vector<float> memory;               // elastic memory: the contact offset kept by plastic
                                           // and viscoelastic vertices (nvert, m, <= 0)
  std::vector<std::int16_t> contact_body;  // partner body per vertex, -1 none (nvert)
  std::vector<float> pressure;             // contact pressure per vertex (nvert), Pa: k * depth
                                           // plus the cores' (prop.hpp "The contact law")
  std::vector<float> depth;                // rigid-pose penetration per vertex (nvert), m
  std::vector<std::uint8_t> flags;         // kVertex* bits (nvert)
  std::vector<BodyContact> contacts;       // per partner body this frame
  DeformCounters counters;
  double time = 0.0;     // time of the last frame
  bool started = false;  // a frame has run (time is valid)

  // The acceleration machinery's scratch (deform_scratch.hpp, internal to deformSkin): sized by
  // initDeformState, deep-copied with the state; a moved-from state has none (initDeformState
  // it again before use).
  std::unique_ptr<DeformScratch> scratch;

  DeformState();
  ~DeformState();
  DeformState(const DeformState& other);
  DeformState& operator=(const DeformState& other);
  DeformState(DeformState&& other) noexcept;
  DeformState& operator=(DeformState&& other) noexcept;
};

// Sizes a state for a model and its skin's triangles (validated: indices < nvert). The
// state starts at rest (zero offsets and memory).
Status initDeformState(const ImplicitModel& model, std::span<const std::uint32_t> indices,
                       DeformState& state);

// What a body carries from frame to frame, copied into the state of the same body in a
// rebuilt scene (a member joined or left, a ball spawned): the warm starts (offset,
// free_offset), the elastic memory (dents of plastic and viscoelastic parts) and the time
// of the last frame. Returns false, changing nothing, when the vertex counts differ.
bool carryDeformState(const DeformState& from, DeformState& to);

// Another site's elastic memory for the same body (one entry per vertex, metres <= 0; e.g.
// a dent record applied, common/scene/dent_record.hpp) replaces the state's: the body then
// draws that site's dents, and its own plastic or viscoelastic behaviour goes on from them.
// A vertex whose own primitive is elastic keeps none (it would never recover). age_s: how
// long ago the memory was sampled; a viscoelastic vertex recovers over it as without contact
// (updateElasticMemory), so a late copy matches the site that made it. Returns false,
// changing nothing, when the vertex counts differ, an entry is not finite and <= 0, or the
// age is negative or not finite.
bool adoptElasticMemory(const ImplicitModel& model, std::span<const float> memory,
                        DeformState& state, float age_s = 0.0f);

// Steps 2 and 3 for body `self` of the scene `bodies` (its posed primitives must be
// bodies[self].posed), given Step 1's interaction list over the same bodies. Writes
// state.positions, normals, flags, counters, contacts; updates warm starts and memory.
// pool: optional; results are bit-identical with any thread count.
void deformSkin(const ImplicitModel& model, std::span<const BodyView> bodies, int self,
                const InteractionList& interactions, const DeformInput& input, DeformState& state,
                const DeformOptions& options = {}, TaskPool* pool = nullptr);

// The function Step 2 solves for vertex v at point p (a positive multiple of F(P) - T
// near the solution), with the colliders and deepest penetrations of the last deformSkin
// call on `state` (same bodies, same input). For tests and tools; allocates nothing.
float vertexFunction(const ImplicitModel& model, std::span<const BodyView> bodies, int self,
                     const DeformInput& input, const DeformState& state,
                     const DeformOptions& options, int v, const glm::vec3& p,
                     glm::vec3* gradient = nullptr);

// Contact between two bodies this frame, made exactly equal and opposite: the force on
// body_a is half the difference of what each side's faces measured (or the one side's
// measure when only one side was deformed).
struct PairContact {
  int body_a = 0;
  int body_b = 0;
  glm::dvec3 force_on_a{0.0};  // N; body_b gets -force_on_a
  double area_a = 0.0;         // m^2 of body_a's contact faces
  double area_b = 0.0;
};

// From the states of all bodies of a scene (null for bodies not deformed this frame).
// Self-contacts give force 0 (internal). `out` is cleared first.
void combineContacts(std::span<const DeformState* const> states, std::vector<PairContact>& out);

// Net contact force on `body` (N) from a combined list.
glm::dvec3 netContactForce(std::span<const PairContact> pairs, int body);

}  // namespace vistel
