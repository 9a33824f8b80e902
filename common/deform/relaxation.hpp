// Internal to common/deform (not a public header). The last parts of Step 2, after the vertex
// solve (DESIGN.md §3 "The hard case"):
//   tangential relaxation (Vaillant et al. 2013, "Implicit skinning"): every joint vertex the
//     solve moved by more than DeformOptions::relax_min_offset (or along -grad F) moves within
//     its tangent plane towards its one-ring's rest barycentre, then is projected back onto
//     F = T along the field normal; relax_passes Jacobi passes over the chunks in parallel;
//   smoothing of corrections: the corrections c = P' - P of the joint regions move towards
//     their one-ring's mean (DeformOptions::smooth_passes), except where a collision term
//     shaped the solution (collisionShaped).
// Space: world, metres. Cost: O(relaxed vertices x passes x a solve) and O(smoothed vertices x
// ring size x passes); no allocation. Results do not depend on the thread count.
#pragma once

#include <cstdint>

#include "common/deform/deform_scratch.hpp"
#include "common/deform/task_pool.hpp"

namespace vistel {

// The relaxation passes over the vertices pass B listed (DeformScratch::relax_list), writing
// positions and marking the moved vertices' rings for new normals.
void relaxJointVertices(DeformFrame& fr, TaskPool* pool);

// Whether a collision term may have shaped vertex v's solution this frame (in contact,
// penetrating in the rigid pose, or a candidate that may bulge it).
bool collisionShaped(const DeformFrame& fr, std::uint32_t v);

// Smooths the joint regions' corrections (serial, vertex order). Returns how many vertices moved.
int smoothCorrections(DeformFrame& fr);

}  // namespace vistel
