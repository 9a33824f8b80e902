// Internal to common/deform (not a public header: include it from deform's own .cpp files
// only). The acceleration machinery of deformSkin behind DeformState's private pointer: what
// it sizes once per body (vertex patches, adjacency, lane sets, lists), what it rebuilds each
// frame (the collider table, the packed own fields, the candidate cache), and the per-call
// context every pass takes (DeformFrame). Results and carried state stay in DeformState.
//
// Space: world (as DeformInput), metres. Sizes: nvert skin vertices, nface triangles, nprim
// primitives of the body. Cost: initDeformScratch O(nvert + nface) with allocation (once);
// nothing here allocates per frame once the largest interaction list has been seen.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "common/deform/collision_terms.hpp"
#include "common/deform/deform.hpp"
#include "common/deform/field_lanes.hpp"

namespace vistel {

// A vertex that moved less than this keeps the rigid normals around it (Step 3).
inline constexpr float kReshapeOffset = 1e-4f;
// A vertex at its solution is on the contact surface when its deepest partner term is
// within this of the penetration zone.
inline constexpr float kContactTolerance = 1e-5f;
// A rigid-pose penetration shallower than this (metres) is not a contact: it is below what
// float round-off in the pose can decide (a vertex grazing its partner's skin would be in
// contact in one frame of reference and not in another).
inline constexpr float kMinContactDepth = 1e-6f;
inline constexpr float kDefaultStiffness = 3.0e4f;
// A collider is a candidate for a vertex only when the rigid position lies within this
// margin of the collider's support box (a vertex outside the support has its root where
// the collider contributes nothing unless its own root is this far away).
inline constexpr float kCullMargin = 0.01f;
// Vertex patches: at most this many vertices each, and this many patches per pass A task.
inline constexpr std::uint32_t kPatchSize = 32;
inline constexpr int kPatchesPerTask = 16;

// Scratch of one deformed body, sized once (initDeformScratch); internal to deformSkin.
struct DeformScratch {
  struct Collider {
    std::uint16_t body = 0;
    std::uint16_t prim = 0;
    const PosedPrimitive* posed = nullptr;
    Bounds cull;                  // support box grown by a margin: farther vertices skip it
    float cull_distance = 0.0f;   // skeleton distance beyond which a vertex skips it
    float inv_unit = 1.0f;        // skeleton-distance units per metre (cone-sphere: at most
                                  // 1 / its smaller radius)
    std::uint32_t pmax_bits = 0;  // deepest penetration this frame (float bits, >= 0)
  };
  std::vector<Collider> colliders;
  std::vector<std::uint32_t> prim_collider_offsets;  // (nprim + 1)
  std::vector<std::uint16_t> prim_colliders;
  std::vector<std::int32_t> always_collider;  // (nprim) collider of an always-pair prim
  std::vector<std::int16_t> always_prims;     // prims named by kPairAlways pairs
  // (nprim) 1: a primitive the builder made for free vertices (adoptFreeVertices; its name
  // is "<part>/<joint>"). Within its own body it is no primitive's collider, and its
  // vertices take an own-body partner's whole contact (as free vertices do): self-contact
  // stays as it was before adoption, at its cost; other bodies meet it as any primitive.
  // Its vertices get no propagation bulge (a capsule fitted to a shell of skin, such as a
  // chest, asks for bulges beyond their move bound: they were held).
  std::vector<std::uint8_t> adopted;
  std::vector<std::uint32_t> vf_offsets;  // vertex -> incident faces (nvert + 1)
  std::vector<std::uint32_t> vf_faces;
  std::vector<std::uint32_t> face_vertices;  // the triangles (3 * ntri)
  // Vertex patches (pass A culls colliders per patch): vertices sharing their defining
  // primitives, in compact groups over the mesh.
  std::vector<std::uint32_t> order;                 // (nvert) vertices, patch by patch
  std::vector<std::uint32_t> patch_offsets;         // (npatch + 1) into order
  std::vector<std::uint32_t> patch_always_offsets;  // (npatch + 1) into patch_always
  std::vector<std::int16_t> patch_always;           // always-pair primitives per patch
  std::vector<float> patch_max_w;                   // (npatch) largest calibration weight
  std::vector<std::uint8_t> cand_count;             // candidates per vertex (nvert; bit 7:
                                                    // more were dropped)
  // A vertex's candidate collider, with what pass A found of it (one struct, so that a
  // vertex's candidates share a cache line or two).
  struct CandidateSlot {
    float iso = 0.5f;            // the pair's threshold
    float reach = 0.0f;          // the largest x = omega F_i - iso within the vertex's cull margin
    float omega = 1.0f;          // the partner field's scale: its skin weight near the vertex, 1
                                 // for a rigid partner
    float x_rigid = -INFINITY;   // a free vertex's x = omega F_i - iso at its rigid position
                                 // (-infinity outside the partner's box), as its solve would
                                 // evaluate it
    std::uint16_t collider = 0;  // index into colliders
  };
  std::vector<CandidateSlot> candidates;    // (nvert * kMaxCandidates)
  std::vector<std::uint8_t> dirty;          // needs a new normal (nvert)
  std::vector<glm::vec3> face_cross;        // twice the area-weighted normal of
                                            // faces with a dirty vertex (nface)
  std::vector<glm::vec3> relaxed;           // relaxation pass output (nvert)
  std::vector<std::uint32_t> relax_list;    // (nvert) the vertices to relax, each
                                            // chunk's from its first vertex on
  std::vector<std::uint32_t> joint_prefix;  // (nvert + 1) joint vertices before each
  std::vector<std::byte> relax_problems;    // room for a problem per joint vertex: the
                                            // relaxed vertices' as pass B gathered them,
                                            // a chunk's from joint_prefix[its first
                                            // vertex] on in relax_list order
  std::vector<std::uint32_t> contact_list;  // (nvert) the vertices in contact, each
                                            // chunk's from its first vertex on
  bool any_inelastic = false;  // a primitive is plastic or viscoelastic (free_offset is kept)
  std::vector<std::uint8_t> fixed_kind;          // rigid limb or free vertex (nvert)
  std::vector<std::uint8_t> resting;             // pass B: fixed, nothing near (nvert)
  std::vector<std::uint8_t> lone_kind;           // limb vertex of one primitive, no bone, not
                                                 // fixed (nvert; see loneKind)
  std::vector<std::uint32_t> solve_list;         // (nvert) pass B: the vertices solved the full
                                                 // way, each chunk's from its first vertex on
  std::vector<std::uint32_t> lone_list;          // (nvert) pass B: the lone limb vertices, each
                                                 // chunk's from its first vertex on
  std::vector<std::uint32_t> smooth_pool;        // joint vertices and the free ones
                                                 // beside them (init)
  std::vector<std::uint32_t> smooth_list;        // those smoothed this frame (capacity:
                                                 // the pool's size)
  std::vector<glm::vec3> correction;             // their corrections (nvert), and the
  std::vector<glm::vec3> correction_next;        // next pass's (Jacobi)
  std::vector<std::uint8_t> smooth_mark;         // in smooth_list (nvert; 0 between frames)
  std::vector<std::uint32_t> orient_vertices;    // face orientation guard: vertices (nvert
  std::vector<std::uint32_t> orient_faces;       // capacity) and inverted faces (ntri)
  std::vector<std::uint8_t> orient_vertex_mark;  // (nvert; 0 between frames)
  std::vector<std::uint8_t> orient_face_mark;    // (ntri; 0 between frames)
  std::vector<glm::vec3> field_gradient;         // relaxed vertices: grad g where (or within
                                                 // a final Newton step of where) the last
                                                 // solve left them (NaN: not known)
  std::vector<DeformCounters> chunk_counters;
  std::vector<glm::mat4> prim_to_world;  // (nprim) bind-pose model space -> world, per
                                         // primitive's bone this frame
  float bulge_allowance = 0.0f;          // this frame: the bulge any vertex may take (m)
  // The own primitives of joint vertices and of limb vertices with a bone, packed to be
  // evaluated together (field_lanes.hpp): a set per distinct (p0, p1, p2, bone).
  std::vector<std::int16_t> lane_set;                       // (nvert) the vertex's set, or -1
  std::vector<std::array<std::int16_t, 4>> lane_set_prims;  // per set
  std::vector<FieldLanes> own_lanes;                        // per set, packed each frame
  std::vector<std::uint8_t> lane_set_packed;  // per set: 0 when a primitive is not covered
};

// What every pass of one deformSkin call reads: the call's arguments and the body's state and
// scratch.
struct DeformFrame {
  const ImplicitModel* model = nullptr;
  std::span<const BodyView> bodies;
  int self = 0;
  const DeformInput* in = nullptr;
  DeformState* st = nullptr;
  DeformScratch* sc = nullptr;
  const DeformOptions* opt = nullptr;
  const PosedPrimitives* posed = nullptr;
  float dt = 0.0f;
  int nvert = 0;
  int chunk = 512;
};

// The vertex chunks of a frame (parallel tasks of fr.chunk vertices; the last may be short).
inline int chunkCount(const DeformFrame& fr) { return (fr.nvert + fr.chunk - 1) / fr.chunk; }
inline std::pair<int, int> chunkRange(const DeformFrame& fr, int c) {
  return {c * fr.chunk, std::min(fr.nvert, (c + 1) * fr.chunk)};
}

// The stiffness of vertex v's own primitive (Pa per metre; kDefaultStiffness for a vertex
// with none).
inline float ownStiffness(const DeformFrame& fr, int v) {
  const std::int16_t p0 = fr.model->calibration.prims[static_cast<std::size_t>(v)][0];
  return p0 >= 0 ? fr.model->primitives.items[static_cast<std::size_t>(p0)].stiffness
                 : kDefaultStiffness;
}

// The elastic behaviour of vertex v's own primitive (elastic for a vertex with none).
inline Elasticity vertexElasticity(const DeformFrame& fr, int v) {
  const std::int16_t p0 = fr.model->calibration.prims[static_cast<std::size_t>(v)][0];
  return p0 >= 0 ? fr.model->primitives.items[static_cast<std::size_t>(p0)].elasticity
                 : Elasticity::kElastic;
}

// Marks vertex v and its one-ring as needing new normals (other chunks may mark the same
// vertices: relaxed atomic stores of the same value, so the result does not depend on order).
inline void markReshaped(const DeformFrame& fr, int v) {
  const Calibration& cal = fr.model->calibration;
  const auto vi = static_cast<std::size_t>(v);
  std::uint8_t* const dirty = fr.sc->dirty.data();  // a local: see passSolve
  const std::uint32_t* const ring = cal.ring.data();
  const std::uint32_t end = cal.ring_offsets[vi + 1];
  std::atomic_ref<std::uint8_t>(dirty[vi]).store(1, std::memory_order_relaxed);
  for (std::uint32_t k = cal.ring_offsets[vi]; k < end; ++k) {
    std::atomic_ref<std::uint8_t>(dirty[ring[k]]).store(1, std::memory_order_relaxed);
  }
}

// Sizes the scratch for a model and its skin's triangles (validated by the caller): adjacency,
// patches, lane sets, lists. deform_scratch.cpp.
void initDeformScratch(const ImplicitModel& model, std::span<const std::uint32_t> indices,
                       DeformScratch& sc);

// Setup of a frame (deform_scratch.cpp): this frame's collider table (the partners Step 1 found
// for each own primitive, plus the same-body primitives named by always-pairs), and the own
// fields' lanes packed from this frame's posed primitives.
void buildColliders(DeformFrame& fr, const InteractionList& list);
void packLaneSets(DeformFrame& fr);

// Pass A (penetration_pass.cpp) over patches [first, last): each vertex's collision
// candidates (the cache), its rigid-pose penetration (depth, pressure) and each collider's
// deepest penetration p_max. The reference way (DeformOptions::reference) over vertices
// [first, last): the same, every collider of the vertex's interaction list tested directly.
void passPenetration(DeformFrame& fr, int first, int last);
void passPenetrationReference(DeformFrame& fr, int first, int last);

}  // namespace vistel
