// An implicit model for any small test avatar (no offline builder, no shared data): a
// sphylinder along each joint's bone to its first child, a sphere on each leaf joint,
// every vertex a limb vertex of its dominant joint's primitive, calibrated on the skin.
// Same-body collisions: every pair of primitives whose joints are neither the same nor
// parent and child (siblings collide: arms against the head). Header-only; needs
// vistel_deform and vistel_avatar.
#pragma once

#include <string>
#include <vector>

#include <fmt/format.h>

#include "common/anim/skeleton.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/deform/calibrate.hpp"
#include "common/deform/implicit_model.hpp"

namespace vistel::test {

// Adds avatar.implicit (radius r_in of every primitive, field bound r_out = reach * r_in).
// Returns false (implicit left empty) when calibration fails.
inline bool addImplicitModel(AvatarModel& avatar, float radius = 0.12f, float reach = 1.7f) {
  const Skeleton& s = avatar.skeleton;
  const int n = s.jointCount();
  const auto rest = restModelTransforms(s);
  ImplicitModel model;
  PrimitiveSet& set = model.primitives;
  for (int j = 0; j < n; ++j) {
    int child = -1;
    for (int c = j + 1; c < n && child < 0; ++c) {
      if (s.parents[static_cast<std::size_t>(c)] == j) child = c;
    }
    Primitive p;
    p.name = fmt::format("p{}_{}", j, s.names[static_cast<std::size_t>(j)]);
    p.bone = j;
    p.shape.a = glm::vec3(rest[static_cast<std::size_t>(j)][3]);
    if (child >= 0) {
      p.shape.kind = ShapeKind::kSphylinder;
      p.shape.b = glm::vec3(rest[static_cast<std::size_t>(child)][3]);
    } else {
      p.shape.kind = ShapeKind::kSphere;
    }
    prepareShape(p.shape);
    p.r_in = radius;
    p.r_out = radius * reach;
    p.weight = shapeWeight(p.density, set.iso, p.r_in, p.r_out);
    set.items.push_back(p);
  }
  // Collisions between primitives of unrelated joints.
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const bool related = s.parents[static_cast<std::size_t>(j)] == i ||
                           s.parents[static_cast<std::size_t>(i)] == j;
      if (!related) {
        model.graph.collide_pairs.push_back(
            {static_cast<std::uint16_t>(i), static_cast<std::uint16_t>(j)});
      }
    }
  }
  finalizeGraph(model.graph, n);
  // Every vertex a limb vertex of its dominant joint's primitive (primitive j = joint j).
  const SkinMesh& m = avatar.skin;
  const std::size_t nv = m.positions.size();
  const auto k = static_cast<std::size_t>(m.influences);
  Calibration& c = model.calibration;
  c.vertex_class.assign(nv, VertexClass::kLimb);
  c.prims.assign(nv, {kNoPrimitive, kNoPrimitive, kNoPrimitive, kNoPrimitive});
  c.rigid.assign(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < k; ++i) {
      if (m.weights[v * k + i] > m.weights[v * k + best]) best = i;
    }
    c.prims[v][0] = static_cast<std::int16_t>(m.joints[v * k + best]);
  }
  computeRelaxationWeights(m.positions, m.normals, m.indices, c);
  if (!calibrateModel(model, m.positions, m.normals)) return false;
  avatar.implicit = std::move(model);
  return true;
}

}  // namespace vistel::test
