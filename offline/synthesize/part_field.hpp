// The field of a part near its rim: the signed distance from a point to the tangent plane
// of the part's surface at the point's nearest surface point (the normal there
// interpolated from the vertex normals). Inside the part's surface (behind it) the value
// is negative, outside positive; beyond an open rim the field continues the surface along
// its tangent plane, so two parts separated by a gap or a cut band can be blended into
// one surface (seam_loft.hpp's optional projection); its nearest points and normals place
// the chords across shared rims (shared_rim.hpp). Robust to open, noisy rims: it needs no
// inside/outside of a closed mesh, only the part's consistent orientation.
//
// Ownership: keeps a reference to the part, which must outlive the field. Space: the
// part's (metres). Cost: one BVH nearest-point query per evaluation (triangle_tree.hpp).
#pragma once

#include <glm/glm.hpp>

#include "offline/compare/triangle_tree.hpp"
#include "offline/synthesize/part_mesh.hpp"

namespace vistel {

struct FieldSample {
  float value = 0.0f;      // signed distance to the tangent plane, metres
  glm::vec3 normal{0.0f};  // unit normal there (the field's gradient)
  float distance = 0.0f;   // to the nearest surface point, metres
  glm::vec3 point{0.0f};   // the nearest surface point
};

class PartField {
 public:
  explicit PartField(const PartMesh& part);

  FieldSample at(const glm::vec3& p) const;

 private:
  const PartMesh& part_;
  TriangleTree tree_;
};

}  // namespace vistel
