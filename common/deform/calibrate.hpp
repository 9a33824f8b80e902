// Calibration of an implicit model on its prototype skin (DESIGN.md §3 "Calibration"):
// every vertex must already sit on its surface in the rest posture, so
//   w_v = T / D_v(P_rest),
// and contacts that already exist at rest (armpit, crotch, a joint vertex inside its
// opposite limb) are calibrated in: each such vertex-primitive pair gets its own raised
// threshold, so the rest posture moves nothing while deeper contacts still act.
// Runtime code (props build their models at run time); the offline builder calls it too.
#pragma once

#include <cstdint>
#include <span>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"

namespace vistel {

struct FieldCalibrationOptions {
  float rest_margin = 0.1f;     // pairs within T * rest_margin of touching at rest get a
                                // threshold of (their rest value + T * rest_margin)
  float always_margin = 0.02f;  // same for a joint vertex's opposite limb
  float min_density = 0.05f;    // D_v(P_rest) below T * this: the vertex becomes free
};

struct CalibrationReport {
  int limb = 0;
  int joint = 0;
  int free = 0;
  int demoted = 0;     // limb/joint vertices made free (their field was too weak at rest)
  int rest_pairs = 0;  // raised-threshold pairs
  int inner = 0;       // inner-layer vertices (Calibration::rigid = kRigidInner; also free)
};

// Fills calibration.w, slope and the pairs from vertex_class and prims (which the caller
// set: p0 and, for joint vertices, p1 = own-side limb, p2 = opposite limb), with the graph
// finalized. rest_positions and rest_normals: the prototype skin (nvert), bind-pose model
// space. Keeps the ring arrays and the rigid flags if already sized (clearing the flag of
// demoted vertices), else leaves them empty per vertex / not rigid.
// also_fits (nvert, or empty): a primitive per vertex that fits its skin weights to the
// vertex as well as to those it defines (see fitSkinWeights; -1: none): the vertices given a
// primitive of their own by adoptFreeVertices (offline/build/free_vertex_adoption.hpp),
// which their former owner fitted, so that its skin stays where it was.
// keep_grids (nprim, or empty): primitives whose skin weight grid is kept as it is, not
// fitted again: a recalibration's caller that knows their fitted vertices did not change
// (the fit is deterministic, so the grid would come out the same).
Result<CalibrationReport> calibrateModel(ImplicitModel& model,
                                         std::span<const glm::vec3> rest_positions,
                                         std::span<const glm::vec3> rest_normals,
                                         const FieldCalibrationOptions& options = {},
                                         std::span<const std::int16_t> also_fits = {},
                                         std::span<const std::uint8_t> keep_grids = {});

// Fits every primitive's skin weight grid (Primitive::skin_weight) so that its skin
// w_i F_i = T passes through, or just outside, the vertices it defines (limb and joint
// vertices with p0 = it, and free ones flagged in `demoted` (nvert, or empty): those made
// free for a weak field at rest, which still move with it): each asks for
// w = T / F_i(P_rest). samples^3 values over its support box at rest, by weighted least
// squares of the grid's trilinear interpolation at those vertices' keys (skinWeightKey: w is
// looked up where a point's ray from the skeleton crosses a fixed shell, so it is constant
// along each ray) with a small membrane term that keeps neighbouring samples close and fills
// those no vertex is near; rounds that weigh more the vertices left outside, then a last
// pass raising the samples around any vertex still short, so a partner (a rigid ball)
// meets the skin before it sinks into it. Clamped to [kMinSkinWeight, kMaxSkinWeight]. A
// primitive that defines no vertex gets none (w = 1). calibrateModel calls it. Cost: a few
// sparse solves of samples^3 unknowns per primitive (offline).
void fitSkinWeights(ImplicitModel& model, std::span<const glm::vec3> rest_positions,
                    std::span<const std::uint8_t> demoted = {}, int samples = 16);

// Tangential relaxation weights (Vaillant et al. 2013): for each vertex, its one-ring
// and mean-value coordinates of the vertex in the ring projected on its tangent plane
// (uniform weights where the ring is open, non-manifold or not star-shaped), so that the
// rest mesh is a fixed point of the relaxation. Fills ring_offsets, ring, ring_weights.
void computeRelaxationWeights(std::span<const glm::vec3> rest_positions,
                              std::span<const glm::vec3> rest_normals,
                              std::span<const std::uint32_t> indices, Calibration& calibration);

}  // namespace vistel
