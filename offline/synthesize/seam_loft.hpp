// The surface of one blend region: a loft between the parent part's rim and the child
// part's rim at a joint, stitched to both (the paper's Section 2: blend the parts in the
// region, polygonize it, join the patch to each part without holes).
//
// 1. Both rims are parametrised by arc length u in [0, 1) in the same sense; the child's
//    parameter is turned by the shift that best lays its shape (centred) onto the
//    parent's.
// 2. Rings between them: for each of N parameters a cubic Hermite curve from the parent's
//    rim point to the child's, leaving each rim along its part's tangent plane (the
//    rim-to-rim direction without its normal part, so the surfaces continue smoothly
//    into the region), sampled at M inner stations s.
// 3. Optionally (LoftOptions::newton_steps), each ring vertex is pulled onto the blended
//    field (1 - w(s)) f_parent + w(s) f_child (part_field.hpp, w = smoothstep) by Newton
//    steps along the blended gradient, each bounded by half the ring spacing. Off by
//    default: on MakeHuman's 3 cm round trip the tangent-plane fields of jagged cut rims
//    moved ring vertices away from the original surface (elbow: worst 3.9 mm on the
//    Hermite curves, 16.6 mm after 4 steps); the Hermite curves already leave each part
//    along its surface.
// 4. Triangles: ring to ring, and the first and last rings zipped onto the rims' own
//    vertices by parameter (no rim vertex moves or is repeated); triangles run opposite to
//    each part's along its rim, so the region is an annulus oriented with the parts: a
//    closed 2-manifold when every rim is lofted.
//
// Space: model space, metres. Cost: O(N x M) field queries (N ring vertices, M rings);
// allocates its output.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "offline/synthesize/part_field.hpp"

namespace vistel {

// A rim as lofted: vertices in output numbering with their positions and unit surface
// normals, closed, in the sense of its own part's triangles (a rim of the parent part, or
// a piece of one closed by a chord across a shared region; a rim of the child part).
struct RimCurve {
  std::vector<std::uint32_t> index;
  std::vector<glm::vec3> position;
  std::vector<glm::vec3> normal;
};

// One side of a region: its rim and its part's field.
struct LoftSide {
  const RimCurve* rim = nullptr;
  const PartField* field = nullptr;
};

// A point on a rim between two of its entries (positions in RimCurve): a + t (b - a).
struct RimPoint {
  std::uint32_t a = 0, b = 0;
  float t = 0.0f;
};

struct LoftOptions {
  float ring_spacing_m = 0.0f;  // between rings; 0: the rims' mean edge length
  int newton_steps = 0;         // projection steps per ring vertex (see above)
};

struct SeamLoft {
  std::vector<glm::vec3> positions;  // new vertices, ring by ring (rings x ring_size)
  std::vector<float> s;              // per new vertex: 0 at the parent's rim, 1 at the child's
  std::vector<RimPoint> parent_at, child_at;  // per new vertex: the rim points it runs between
  std::vector<std::uint32_t> indices;         // triangles in output numbering (3 each)
  int rings = 0;
  int ring_size = 0;
  float length = 0.0f;          // mean rim-to-rim distance, metres
  float max_projection = 0.0f;  // largest distance a ring vertex moved onto the field, m
};

// The loft between `parent` and `child`; its new vertices are numbered from
// `first_new_vertex` in `indices`. Both rims with at least 3 vertices.
SeamLoft loftSeam(const LoftSide& parent, const LoftSide& child, std::uint32_t first_new_vertex,
                  const LoftOptions& options = {});

}  // namespace vistel
