// Level of detail for the deformable component (issue 19): which bodies of a room run
// Steps 2-3 every frame, which at a lower rate, and which are drawn with rigid skinning
// only, chosen afresh every frame.
//
//   kFull     Steps 2-3 every frame: bodies near the viewer, and bodies in contact with
//             another body or a prop (Step 1 found a pair between them this frame).
//   kReduced  Steps 2-3 on one frame in `reduced_every` (staggered by body index, so the
//             work spreads evenly over frames); in between the body is drawn with the
//             offsets of its last deformation added to its rigid skinning.
//   kRigid    rigid skinning only (far away, or over the budget).
//
// Distances are measured in the floor plane (x, z of room space, metres): bodies stand on
// the floor and the viewer's height does not matter. A body keeps its previous, better
// tier until it is `hysteresis_m` past the radius, so a body at a boundary does not switch
// every frame. Budgets: at most max_full bodies at full rate (bodies in contact first, then
// the nearest); the others that wanted it drop to kReduced; at most max_reduced at the
// lower rate (the nearest), the others drop to kRigid. Ties go to the lower body index, so
// the result is deterministic.
//
// Used by the client's RoomDeformer (client/deform) and configured by [lod] in
// config/client.toml. Pure functions: no state but the caller's scratch; O(n log n) for n
// bodies; allocation only while the scratch grows to the room's size.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

enum class DeformTier : std::uint8_t { kFull = 0, kReduced = 1, kRigid = 2 };

struct DeformLodSettings {
  bool enabled = true;            // false: every body kFull (the component without LOD)
  float full_radius_m = 2.6f;     // within this: kFull (the nearest ring of a room and more)
  float reduced_radius_m = 6.0f;  // within this (beyond full_radius_m): kReduced; beyond: kRigid
  float hysteresis_m = 0.25f;     // keep a better previous tier up to this far past its radius
  int reduced_every = 3;          // kReduced bodies deform on one frame in this many (>= 1)
  int max_full = 12;              // at most this many kFull bodies per frame (>= 0)
  int max_reduced = 48;           // at most this many kReduced bodies per frame (>= 0)
  bool contact_full = true;       // a body in contact with another body is kFull
};

// Settings the client can use: radii finite, 0 <= full <= reduced, hysteresis >= 0,
// reduced_every in 1..60, budgets >= 0. The error begins with the field's name.
Status validateDeformLodSettings(const DeformLodSettings& settings);

// One frame's inputs (nbody = positions.size()).
struct DeformLodInput {
  std::span<const glm::vec3> positions;      // where each body stands, room space (nbody)
  glm::vec3 viewer{0.0f};                    // the viewer, room space
  std::span<const std::uint8_t> in_contact;  // nbody (1: touches another body this frame),
                                             // or empty (none in contact)
  std::span<const DeformTier> previous;      // last frame's tiers (nbody), or empty
};

// Sorting scratch, reused between frames.
struct DeformLodScratch {
  std::vector<float> distance;  // (nbody) floor-plane distance to the viewer
  std::vector<int> order;       // (nbody) body indices in priority order
};

// Chooses every body's tier (out: nbody, written entirely). Spans of the wrong size are
// treated as empty (in_contact, previous); out must have nbody entries (else nothing is
// written). Non-finite positions are treated as infinitely far (kRigid).
void chooseDeformTiers(const DeformLodSettings& settings, const DeformLodInput& input,
                       DeformLodScratch& scratch, std::span<DeformTier> out);

// Whether a body of this tier runs Steps 2-3 on frame `frame`: kFull always, kRigid never,
// kReduced when (frame + body) is a multiple of reduced_every (values < 1 count as 1).
bool deformsOnFrame(DeformTier tier, int body, std::int64_t frame, int reduced_every);

struct DeformTierCounts {
  int full = 0;
  int reduced = 0;
  int rigid = 0;
};
DeformTierCounts countTiers(std::span<const DeformTier> tiers);

}  // namespace vistel
