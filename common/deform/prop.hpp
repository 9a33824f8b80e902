// Props: bodies with their own primitives and (optionally) a skin, e.g. a ball
// (DESIGN.md §6). A ball is one sphere primitive on a one-joint skeleton whose only
// transform is the ball's placement; soft or rigid, with an elasticity over time.
#pragma once

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/deform/implicit_model.hpp"

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

}  // namespace vistel
