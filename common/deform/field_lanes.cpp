#include "common/deform/field_lanes.hpp"

namespace vistel {

bool packFieldLane(const PosedPrimitive* prim, int lane, FieldLanes& l) {
  // The lane's parameters, then written in one go (a rejected primitive changes nothing).
  glm::vec3 a(0.0f), e1(0.0f), e2(0.0f);
  float lo1 = 0.0f, hi1 = 0.0f, lo2 = 0.0f, hi2 = 0.0f, ra = 1.0f, k = 0.0f;
  float inv_r_out = 0.0f, weight = 0.0f;
  if (prim != nullptr) {
    if (prim->density.kind != DensityKind::kWyvill) return false;
    const Shape& s = prim->shape;
    a = s.a;
    inv_r_out = prim->inv_r_out;
    weight = prim->weight;
    switch (s.kind) {
      case ShapeKind::kSphere:
        break;
      case ShapeKind::kSphylinder:
        e1 = s.axis;
        hi1 = s.length;
        break;
      case ShapeKind::kConeSphere:
        e1 = s.axis;
        hi1 = s.length;
        ra = s.radius_a;
        k = s.cone_slope;
        break;
      case ShapeKind::kOffsetPolygon:
        if (!s.rectangle) return false;
        e1 = s.u;
        e2 = s.v;
        lo1 = s.rect_min.x;
        hi1 = s.rect_max.x;
        lo2 = s.rect_min.y;
        hi2 = s.rect_max.y;
        break;
    }
  }
  l.ax[lane] = a.x;
  l.ay[lane] = a.y;
  l.az[lane] = a.z;
  l.e1x[lane] = e1.x;
  l.e1y[lane] = e1.y;
  l.e1z[lane] = e1.z;
  l.e2x[lane] = e2.x;
  l.e2y[lane] = e2.y;
  l.e2z[lane] = e2.z;
  l.lo1[lane] = lo1;
  l.hi1[lane] = hi1;
  l.lo2[lane] = lo2;
  l.hi2[lane] = hi2;
  l.ra[lane] = ra;
  l.k[lane] = k;
  l.inv_r_out[lane] = inv_r_out;
  l.weight[lane] = weight;
  return true;
}

}  // namespace vistel
