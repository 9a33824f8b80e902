// Evens out a simplified skin: Delaunay edge flips, tangential smoothing and projection
// back onto the implicit surface, on an OpenMesh triangle mesh.
#pragma once

#include "offline/synth/implicit_body.hpp"
#include "offline/synth/polygonize.hpp"

namespace vistel::synth {

struct RelaxStats {
  int flips = 0;           // edges flipped over all rounds
  float max_residual = 0;  // largest |field| at a vertex after the last projection, metres
};

// `rounds` rounds of: flip every edge whose opposite angles sum to more than pi (when the
// flip keeps the surface unfolded), move each vertex half-way to the centroid of its
// neighbours within its tangent plane, project it onto the zero set of `body`. Keeps the
// connectivity a closed 2-manifold (flips only) and the vertex count. Deterministic.
RelaxStats relax(TriangleMesh& mesh, const ImplicitBody& body, int rounds);

}  // namespace vistel::synth
