#include "common/deform/prop.hpp"

#include <cmath>
#include <map>

#include "common/deform/calibrate.hpp"

namespace vistel {
namespace {

void icosphere(float radius, int levels, SkinMesh& m) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<glm::vec3> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                              {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                              {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::uint32_t> f = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7, 10, 0, 10, 11,
                                  1, 5,  9, 5, 11, 4,  11, 10, 2,  10, 7, 6,  7, 1,  8,
                                  3, 9,  4, 3, 4,  2,  3,  2,  6,  3,  6, 8,  3, 8,  9,
                                  4, 9,  5, 2, 4,  11, 6,  2,  10, 8,  6, 7,  9, 8,  1};
  for (glm::vec3& x : p) x = glm::normalize(x);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back(glm::normalize(p[a] + p[b]));
      const auto i = static_cast<std::uint32_t>(p.size() - 1);
      mid.emplace(key, i);
      return i;
    };
    std::vector<std::uint32_t> g;
    for (std::size_t i = 0; i < f.size(); i += 3) {
      const std::uint32_t a = f[i], b = f[i + 1], c = f[i + 2];
      const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      g.insert(g.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f.swap(g);
  }
  m.positions.clear();
  m.normals.clear();
  for (const glm::vec3& x : p) {
    m.positions.push_back(radius * x);
    m.normals.push_back(x);
  }
  m.indices = f;
  m.influences = 1;
  m.joints.assign(p.size(), 0);
  m.weights.assign(p.size(), 1.0f);
}

}  // namespace

Result<PrimitiveSet> makeBallPrimitives(const BallSpec& s) {
  if (!(s.radius > 0.0f) || !std::isfinite(s.radius) || !(s.reach > 1.0f) ||
      !std::isfinite(s.reach) || !(s.stiffness > 0.0f) || !(s.time_constant > 0.0f) ||
      s.subdivisions < 0 || s.subdivisions > 6) {
    return fail(
        "ball: parameters out of range (radius {}, reach {}, stiffness {}, tau {}, "
        "subdivisions {})",
        s.radius, s.reach, s.stiffness, s.time_constant, s.subdivisions);
  }
  PrimitiveSet set;
  Primitive p;
  p.name = "ball";
  p.role = PrimitiveRole::kLimb;
  p.bone = 0;
  p.shape.kind = ShapeKind::kSphere;
  prepareShape(p.shape);
  p.r_in = s.radius;
  p.r_out = s.radius * s.reach;
  p.weight = shapeWeight(p.density, set.iso, p.r_in, p.r_out);
  p.stiffness = s.stiffness;
  p.elasticity = s.elasticity;
  p.time_constant = s.time_constant;
  set.items.push_back(p);
  return set;
}

Result<BallBody> makeBall(const BallSpec& s) {
  Result<PrimitiveSet> set = makeBallPrimitives(s);
  if (!set) return set.error();
  BallBody b;
  b.skeleton.names = {"ball"};
  b.skeleton.parents = {kNoParent};
  b.skeleton.rest_local.resize(1);
  computeInverseBind(b.skeleton);
  icosphere(s.radius, s.subdivisions, b.mesh);
  b.model.primitives = std::move(*set);
  finalizeGraph(b.model.graph, 1);
  const std::size_t nv = b.mesh.positions.size();
  b.model.calibration.vertex_class.assign(nv, VertexClass::kLimb);
  b.model.calibration.prims.assign(nv, {0, kNoPrimitive, kNoPrimitive, kNoPrimitive});
  b.model.calibration.rigid.assign(nv, 1);
  computeRelaxationWeights(b.mesh.positions, b.mesh.normals, b.mesh.indices, b.model.calibration);
  Result<CalibrationReport> rep = calibrateModel(b.model, b.mesh.positions, b.mesh.normals);
  if (!rep) return rep.error();
  return b;
}

}  // namespace vistel
