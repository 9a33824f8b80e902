// What the server keeps of an avatar for the room's collision world (DESIGN.md §6: "the
// server needs only primitives, never meshes"): the skeleton (to pose postures), the
// implicit model's PrimitiveSet and CombinationGraph (Step 1 across and within bodies),
// and where the head is (props spawn above it). The skin and calibration are dropped
// once the upload has been validated. Immutable and shared by every room that uses it.
#pragma once

#include <memory>
#include <string_view>

#include "common/anim/skeleton.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"

namespace vistel::server {

struct CollisionModel {
  Skeleton skeleton;
  bool collides = false;    // the avatar has an implicit model (else it takes no part)
  PrimitiveSet primitives;  // bind-pose model space (empty when !collides)
  CombinationGraph graph;   // finalized (empty when !collides)
  int head_joint = 0;       // joint named "head" (any case), else the highest at rest
};

// Limits a server puts on uploaded collision models, so one avatar cannot make every
// tick expensive (Step 1 is O(m^2) in the worst case) or reach across the room.
struct CollisionLimits {
  int max_primitives = 128;
  float max_extent_m = 2.0f;  // largest side of a primitive's field box in the bind pose
};

// Takes the skeleton and implicit model out of a decoded, validated avatar and checks them
// against the limits; the error names the source, the primitive and the limit.
Result<std::shared_ptr<const CollisionModel>> makeCollisionModel(AvatarModel&& avatar,
                                                                 const CollisionLimits& limits,
                                                                 std::string_view source);

}  // namespace vistel::server
