#include "common/deform/implicit_model.hpp"

#include <algorithm>
#include <cmath>

namespace vistel {
namespace {

bool finitePositive(float x) { return std::isfinite(x) && x > 0.0f; }

}  // namespace

std::string_view primitivePart(std::string_view name) {
  const std::size_t slash = name.find('/');
  return slash == std::string_view::npos ? name : name.substr(0, slash);
}

float shapeWeight(const Density& density, float iso, float r_in, float r_out) {
  return iso / densityValue(density, r_in / r_out);
}

void finalizeGraph(CombinationGraph& g, int n) {
  for (auto& p : g.collide_pairs) {
    if (p[0] > p[1]) std::swap(p[0], p[1]);
  }
  std::sort(g.collide_pairs.begin(), g.collide_pairs.end());
  g.collide_pairs.erase(std::unique(g.collide_pairs.begin(), g.collide_pairs.end()),
                        g.collide_pairs.end());
  g.primitive_count = n;
  g.collide_matrix.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), 0);
  for (const auto& p : g.collide_pairs) {
    if (p[0] >= n || p[1] >= n) continue;  // validateCombinationGraph reports these
    g.collide_matrix[static_cast<std::size_t>(p[0]) * static_cast<std::size_t>(n) + p[1]] = 1;
    g.collide_matrix[static_cast<std::size_t>(p[1]) * static_cast<std::size_t>(n) + p[0]] = 1;
  }
  g.neighbour_matrix.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), 0);
  const auto join = [&g, n](int i, int j) {
    if (i >= n || j >= n) return;  // validateCombinationGraph reports these
    g.neighbour_matrix[static_cast<std::size_t>(i) * static_cast<std::size_t>(n) +
                       static_cast<std::size_t>(j)] = 1;
    g.neighbour_matrix[static_cast<std::size_t>(j) * static_cast<std::size_t>(n) +
                       static_cast<std::size_t>(i)] = 1;
  };
  for (const Blend& b : g.blends) {
    join(b.limb_a, b.limb_b);
    join(b.joint, b.limb_a);
    join(b.joint, b.limb_b);
  }
}

Status validatePrimitiveSet(const PrimitiveSet& s, int joint_count) {
  if (!(s.iso > 0.0f && s.iso < 1.0f)) return fail("primitives: iso {} not in (0, 1)", s.iso);
  if (s.diff_exponent < 1 || s.diff_exponent > 8) {
    return fail("primitives: diff exponent {} not in 1..8", s.diff_exponent);
  }
  if (!std::isfinite(s.propagation_amplitude) || s.propagation_amplitude < 0.0f ||
      !finitePositive(s.propagation_width) || !(s.propagation_width < s.iso)) {
    return fail("primitives: propagation amplitude {} / width {} out of range (width < iso)",
                s.propagation_amplitude, s.propagation_width);
  }
  if (s.items.empty() || s.items.size() > static_cast<std::size_t>(kMaxPrimitives)) {
    return fail("primitives: count {} not in 1..{}", s.items.size(), kMaxPrimitives);
  }
  for (std::size_t i = 0; i < s.items.size(); ++i) {
    const Primitive& p = s.items[i];
    const auto bad = [&](std::string_view why) {
      return fail("primitive {} '{}': {}", i, p.name, why);
    };
    if (p.bone < 0 || p.bone >= joint_count) return bad("bone out of range");
    if (static_cast<int>(p.role) > 2) return bad("unknown role");
    if (static_cast<int>(p.elasticity) > 2) return bad("unknown elasticity");
    if (static_cast<int>(p.shape.kind) > 3) return bad("unknown shape kind");
    if (const char* why = shapeProblem(p.shape); why[0] != '\0') return bad(why);
    if (!validDensity(p.density)) return bad("density parameters out of range");
    if (!finitePositive(p.r_in) || !finitePositive(p.r_out) || !(p.r_in < p.r_out)) {
      return bad("need 0 < r_in < r_out");
    }
    if (!finitePositive(p.weight)) return bad("shape weight must be positive and finite");
    if (!(p.stiffness > 0.0f) || std::isnan(p.stiffness)) return bad("stiffness must be > 0");
    if (!finitePositive(p.time_constant)) return bad("time constant must be > 0");
    const SkinWeightGrid& g = p.skin_weight;
    if (g.n != 0) {
      if (g.n < 2 || g.n > kMaxSkinWeightSamples) return bad("skin weight grid size out of range");
      const auto count = static_cast<std::size_t>(g.n) * static_cast<std::size_t>(g.n) *
                         static_cast<std::size_t>(g.n);
      if (g.values.size() != count) return bad("skin weight grid has the wrong sample count");
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(g.box.min[k]) || !std::isfinite(g.box.max[k]) ||
            !(g.box.min[k] < g.box.max[k])) {
          return bad("skin weight grid box must be finite and non-empty");
        }
      }
      for (const float x : g.values) {
        if (!(x >= kMinSkinWeight && x <= kMaxSkinWeight)) {
          return bad("skin weight sample out of range");
        }
      }
    }
  }
  return {};
}

Status validateCombinationGraph(const CombinationGraph& g, const PrimitiveSet& s) {
  const auto n = static_cast<int>(s.items.size());
  for (std::size_t i = 0; i < g.blends.size(); ++i) {
    const Blend& b = g.blends[i];
    if (b.limb_a >= n || b.limb_b >= n || b.joint >= n || b.limb_a == b.limb_b) {
      return fail("graph: blend {} has bad primitive indices", i);
    }
    if (s.items[b.joint].role != PrimitiveRole::kJoint) {
      return fail("graph: blend {} joint '{}' is not a joint primitive", i, s.items[b.joint].name);
    }
  }
  for (std::size_t i = 0; i < g.collide_pairs.size(); ++i) {
    const auto& p = g.collide_pairs[i];
    if (p[0] >= n || p[1] >= n || p[0] == p[1]) {
      return fail("graph: collide pair {} has bad primitive indices", i);
    }
  }
  if (g.primitive_count != n ||
      g.collide_matrix.size() != static_cast<std::size_t>(n) * static_cast<std::size_t>(n)) {
    return fail("graph: not finalized for {} primitives", n);
  }
  return {};
}

Status validateCalibration(const Calibration& c, const PrimitiveSet& s, int vertex_count) {
  const auto nv = static_cast<std::size_t>(vertex_count);
  const auto np = static_cast<int>(s.items.size());
  if (c.vertex_class.size() != nv || c.prims.size() != nv || c.w.size() != nv ||
      c.slope.size() != nv || c.rigid.size() != nv || c.pair_offsets.size() != nv + 1 ||
      c.ring_offsets.size() != nv + 1) {
    return fail("calibration: arrays do not have {} vertices", vertex_count);
  }
  if (c.ring.size() != c.ring_weights.size()) return fail("calibration: ring sizes differ");
  if (!c.own_weight.empty() && c.own_weight.size() != nv) {
    return fail("calibration: {} own weights for {} vertices", c.own_weight.size(), vertex_count);
  }
  for (std::size_t v = 0; v < c.own_weight.size(); ++v) {
    if (!(c.own_weight[v] >= 0.0f && c.own_weight[v] <= 1.0f)) {
      return fail("calibration: vertex {} own weight {} outside [0, 1]", v, c.own_weight[v]);
    }
  }
  const auto check_offsets = [&](const std::vector<std::uint32_t>& off, std::size_t total,
                                 std::string_view what) -> Status {
    if (off[0] != 0 || off[nv] != total) return fail("calibration: {} offsets do not span", what);
    for (std::size_t v = 0; v < nv; ++v) {
      if (off[v] > off[v + 1])
        return fail("calibration: {} offsets decrease at vertex {}", what, v);
    }
    return {};
  };
  if (Status st = check_offsets(c.pair_offsets, c.pairs.size(), "pair"); !st) return st;
  if (Status st = check_offsets(c.ring_offsets, c.ring.size(), "ring"); !st) return st;
  for (std::size_t v = 0; v < nv; ++v) {
    const auto cls = static_cast<int>(c.vertex_class[v]);
    const auto& p = c.prims[v];
    const auto in_range = [&](std::int16_t i) { return i >= 0 && i < np; };
    const auto none_or_in = [&](std::int16_t i) { return i == kNoPrimitive || in_range(i); };
    if (cls > 2) return fail("calibration: vertex {} has unknown class {}", v, cls);
    if (!none_or_in(p[0]) || !none_or_in(p[1]) || !none_or_in(p[2]) || !none_or_in(p[3])) {
      return fail("calibration: vertex {} names a primitive out of range", v);
    }
    if (c.vertex_class[v] != VertexClass::kFree && !in_range(p[0])) {
      return fail("calibration: vertex {} has no defining primitive", v);
    }
    if (c.vertex_class[v] == VertexClass::kJoint && (!in_range(p[1]) || !in_range(p[2]))) {
      return fail("calibration: joint vertex {} lacks its two limbs", v);
    }
    if (!finitePositive(c.w[v])) return fail("calibration: vertex {} weight not positive", v);
    if (c.rigid[v] > kRigidUntouched ||
        ((c.rigid[v] == kRigidLimb || c.rigid[v] == kRigidUntouched) &&
         (c.vertex_class[v] != VertexClass::kLimb || p[3] >= 0))) {
      return fail("calibration: vertex {} rigid flag invalid", v);
    }
    if (c.rigid[v] == kRigidInner &&
        (c.vertex_class[v] != VertexClass::kFree || p[0] != kNoPrimitive || p[1] != kNoPrimitive ||
         p[2] != kNoPrimitive || p[3] != kNoPrimitive ||
         c.pair_offsets[v] != c.pair_offsets[v + 1])) {
      return fail("calibration: inner-layer vertex {} has a class, primitive or pair", v);
    }
    if (!std::isfinite(c.slope[v]) || c.slope[v] < 0.0f ||
        (c.vertex_class[v] == VertexClass::kFree && !(c.slope[v] > 0.0f))) {
      return fail("calibration: vertex {} slope out of range", v);
    }
  }
  for (std::size_t i = 0; i < c.pairs.size(); ++i) {
    const VertexPair& p = c.pairs[i];
    if (p.prim < 0 || p.prim >= np || !std::isfinite(p.iso) || p.iso < s.iso || p.flags > 1) {
      return fail("calibration: vertex pair {} out of range", i);
    }
  }
  for (std::size_t i = 0; i < c.ring.size(); ++i) {
    if (c.ring[i] >= nv || !std::isfinite(c.ring_weights[i])) {
      return fail("calibration: ring entry {} out of range", i);
    }
  }
  return {};
}

Status validateImplicitModel(const ImplicitModel& m, int joint_count, int vertex_count) {
  if (Status st = validatePrimitiveSet(m.primitives, joint_count); !st) return st;
  if (Status st = validateCombinationGraph(m.graph, m.primitives); !st) return st;
  return validateCalibration(m.calibration, m.primitives, vertex_count);
}

}  // namespace vistel
