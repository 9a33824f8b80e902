// Step 1 of the deformable component (DESIGN.md §3): the interaction list, i.e. which
// primitives' bounding volumes overlap this frame, across bodies (avatars, props) and
// within one body (self-contact between parts that do not blend).
//
// Bounding volume of a primitive: its skeleton swollen by its reach (the points where its
// field is non-zero). Candidates come from sweep-and-prune on world x (a persistent,
// nearly sorted order, so coherent frames cost O(m + k)), then y/z box overlap, then the
// analytic test skeletonGap <= reach_i + reach_j. Worst case O(m^2) for m primitives.
// A server needs only each body's CombinationGraph and posed primitives (no meshes).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"
#include "common/deform/posed_primitives.hpp"

namespace vistel {

// One body of the collision world as Step 1 and Step 2 see it (non-owning), and its motion
// for Step 3's restitution (prop.hpp "The contact law").
struct BodyView {
  const CombinationGraph* graph = nullptr;  // same-body collision filter; null: no self-contact
  const PosedPrimitives* posed = nullptr;   // this frame's posed primitives, world space
  glm::vec3 velocity{0.0f};  // linear velocity, world m/s, where known (a prop's); else 0
  float restitution = 1.0f;  // e in [0, 1] (1: elastic, an avatar's); a pair's is the product
};

struct Interaction {
  std::uint16_t body_a = 0;
  std::uint16_t prim_a = 0;
  std::uint16_t body_b = 0;
  std::uint16_t prim_b = 0;

  friend bool operator==(const Interaction&, const Interaction&) = default;
};

struct InteractionList {
  // Each touching pair once, (body_a, prim_a) < (body_b, prim_b), sorted: what a server
  // sends in a snapshot.
  std::vector<Interaction> pairs;
  // Derived by finalizeInteractions: every pair in both orders, sorted by (body_a, prim_a,
  // body_b, prim_b), and where each body's entries start (nbody + 1).
  std::vector<Interaction> directed;
  std::vector<std::uint32_t> body_offsets;

  // The directed entries whose body_a is `body`.
  std::span<const Interaction> forBody(int body) const {
    if (body < 0 || static_cast<std::size_t>(body) + 1 >= body_offsets.size()) return {};
    return std::span<const Interaction>(directed).subspan(
        body_offsets[static_cast<std::size_t>(body)],
        body_offsets[static_cast<std::size_t>(body) + 1] -
            body_offsets[static_cast<std::size_t>(body)]);
  }
};

// Reused between frames by buildInteractions (sweep-and-prune order and work lists).
struct InteractionScratch {
  std::vector<Bounds> body_boxes;         // each body's collidable primitives' union
  std::vector<std::uint8_t> body_live;    // it has a collidable primitive
  std::vector<std::uint32_t> body_order;  // live bodies by box min x (kept between frames)
  std::vector<std::uint32_t> active;      // the sweep's open bodies
  std::vector<std::uint16_t> near_a;      // a body pair's primitives in their common box
  std::vector<std::uint16_t> near_b;
};

// Step 1 across bodies. Pairs of different bodies collide when both primitives collide;
// pairs within a body when its graph says so. Two levels: each body's own pairs from its
// graph's collide pairs; across bodies, a sweep-and-prune over the bodies' boxes, then
// for each pair of bodies whose boxes meet, the primitives of each inside the common box
// tested against the other's. Cost: O(sum of collide pairs + bodies log bodies + the
// primitives of bodies that nearly touch), so a seated room of a hundred costs a hundred
// bodies' self-contact, not a sweep over every primitive of the room. Allocation-free
// once the vectors have grown to this scene's size. At most 65535 bodies of at most
// kMaxPrimitives each.
// self_contact = false lists only the pairs between bodies (a server that leaves each
// body's own pairs to its clients).
void buildInteractions(std::span<const BodyView> bodies, InteractionScratch& scratch,
                       InteractionList& out, bool self_contact = true);

// Step 1 for a single body (self-contact only): the graph's collide pairs tested directly.
void buildInteractions(const CombinationGraph& graph, const PosedPrimitives& posed,
                       InteractionList& out);

// Appends body `body`'s own pairs (self-contact: its graph's collide pairs whose
// bounding volumes overlap) to pairs, unordered. A pair naming a primitive the posed set
// lacks is skipped (validateInteractions refuses such a body's lists anyway).
void appendSelfInteractions(const CombinationGraph& graph, const PosedPrimitives& posed,
                            std::uint16_t body, std::vector<Interaction>& pairs);

// Whether two posed primitives' bounding volumes overlap (box, then analytic test).
bool boundsOverlap(const PosedPrimitive& p, const PosedPrimitive& q);

// Sorts and dedupes `pairs` (ordering each pair) and fills the derived fields for
// body_count bodies. Call after filling `pairs` by hand (e.g. from a snapshot).
void finalizeInteractions(InteractionList& list, int body_count);

// Checks a received list against the bodies: indices in range, no self-pairs, pairs the
// bodies allow. The message names the entry.
Status validateInteractions(const InteractionList& list, std::span<const BodyView> bodies);

}  // namespace vistel
