// Skin weights for the default avatar by bone heat (Baran & Popovic 2007): each bone's
// weight is the equilibrium of heat diffusing over the skin from the vertices that belong
// to it, so weights vary smoothly across joints and blend over about a limb's thickness.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "offline/synth/polygonize.hpp"

namespace vistel::synth {

struct BoneSegment {
  glm::vec3 head{0.0f};  // joint position, model space
  glm::vec3 tail{0.0f};  // end of the bone (child joint, fingertip, ...)
};

struct SkinWeights {
  int influences = 4;
  std::vector<std::uint16_t> joints;  // nvert * influences
  std::vector<float> weights;         // nvert * influences; each vertex sums to 1, unused 0
};

// mesh: closed 2-manifold; labels: the joint each vertex belongs to (nvert); parents: the
// skeleton (njoint, -1 for the root); bones: one segment per joint (model space).
//  1. Labels are made consistent first: neighbouring vertices get the same joint or a
//     parent and child (a vertex steps along the tree towards a neighbour's label), and
//     where siblings' shares meet (thighs at the crotch, fingers at the webs) the parent
//     takes a band two rings wide.
//  2. A vertex may depend on its joint, that joint's parent and grandparent, the child
//     joint whose bone is nearest and that child's nearest child: never on a sibling
//     branch, so a finger vertex never depends on another finger and a thigh vertex never
//     on the other leg.
//  3. For each joint j, (L + A H) w_j = A H [label == j] is solved over the vertices that
//     may depend on j (w_j = 0 beyond them, so it fades out at their border), with L the
//     cotangent Laplacian (negative cotangents clamped to 0, so weights stay in [0, 1]),
//     A the vertex areas and H = 2 / d^2 (d: distance to the vertex's own bone).
//  4. Three rounds of Jacobi smoothing per joint widen transitions only an edge or two
//     wide; weights below 2% of a vertex's total are dropped by subtraction; the 4 largest
//     are kept and normalised.
// Fails only if a sparse factorisation does (a degenerate mesh). Cost: one small sparse
// Cholesky factorisation and solve per joint (~0.1 s at 10k vertices).
Result<SkinWeights> computeSkinWeights(const TriangleMesh& mesh, std::span<const int> labels,
                                       std::span<const int> parents,
                                       std::span<const BoneSegment> bones);

}  // namespace vistel::synth
