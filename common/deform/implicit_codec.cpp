#include "common/deform/implicit_codec.hpp"

#include <algorithm>

namespace vistel {
namespace {

constexpr std::size_t kMaxName = 256;

void vec3(ByteWriter& w, const glm::vec3& v) {
  w.f32(v.x);
  w.f32(v.y);
  w.f32(v.z);
}
glm::vec3 vec3(ByteReader& r) {
  glm::vec3 v;
  v.x = r.f32();
  v.y = r.f32();
  v.z = r.f32();
  return v;
}

Status finish(const ByteReader& r, std::string_view section) {
  if (!r.ok()) return fail("{}: truncated at byte {}", section, r.offset());
  if (r.remaining() != 0) return fail("{}: {} unexpected trailing bytes", section, r.remaining());
  return {};
}

}  // namespace

void encodePrimitiveSet(const PrimitiveSet& s, ByteWriter& w) {
  w.u32(kPrimitiveSetVersion);
  w.f32(s.iso);
  w.u32(static_cast<std::uint32_t>(s.diff_exponent));
  w.f32(s.propagation_amplitude);
  w.f32(s.propagation_width);
  w.u32(static_cast<std::uint32_t>(s.items.size()));
  for (const Primitive& p : s.items) {
    w.string(p.name);
    w.u8(static_cast<std::uint8_t>(p.role));
    w.u8(static_cast<std::uint8_t>(p.shape.kind));
    w.u8(static_cast<std::uint8_t>(p.density.kind));
    w.u8(static_cast<std::uint8_t>(p.elasticity));
    w.u8(p.collides ? 1 : 0);
    w.i32(p.bone);
    vec3(w, p.shape.a);
    vec3(w, p.shape.b);
    vec3(w, p.shape.u);
    vec3(w, p.shape.v);
    w.f32(p.shape.radius_a);
    w.f32(p.shape.radius_b);
    w.u32(static_cast<std::uint32_t>(p.shape.polygon_count));
    for (const glm::vec2& q : p.shape.polygon) {
      w.f32(q.x);
      w.f32(q.y);
    }
    w.f32(p.r_in);
    w.f32(p.r_out);
    w.f32(p.weight);
    w.f32(p.density.knee);
    w.f32(p.density.slope);
    w.f32(p.stiffness);
    w.f32(p.time_constant);
    const SkinWeightGrid& g = p.skin_weight;
    w.u8(static_cast<std::uint8_t>(g.n));
    if (g.n != 0) {
      vec3(w, g.box.min);
      vec3(w, g.box.max);
      for (const float x : g.values) w.f32(x);
    }
  }
}

Result<PrimitiveSet> decodePrimitiveSet(std::span<const std::uint8_t> bytes, int joint_count) {
  ByteReader r(bytes);
  const std::uint32_t version = r.u32();
  if (r.ok() && version != kPrimitiveSetVersion) {
    return fail("primitive set: version {} (this build reads {})", version, kPrimitiveSetVersion);
  }
  PrimitiveSet s;
  s.iso = r.f32();
  s.diff_exponent = static_cast<int>(r.u32());
  s.propagation_amplitude = r.f32();
  s.propagation_width = r.f32();
  const std::uint32_t n = r.u32();
  constexpr std::size_t kMinItem = 4 + 5 + 4 + 48 + 8 + 4 + 64 + 28;
  if (!r.ok() || n > static_cast<std::uint32_t>(kMaxPrimitives) || n > r.remaining() / kMinItem) {
    return fail("primitive set: bad primitive count {} at byte {}", n, r.offset());
  }
  s.items.resize(n);
  for (std::uint32_t i = 0; i < n && r.ok(); ++i) {
    Primitive& p = s.items[i];
    p.name = r.string(kMaxName);
    p.role = static_cast<PrimitiveRole>(r.u8());
    p.shape.kind = static_cast<ShapeKind>(r.u8());
    p.density.kind = static_cast<DensityKind>(r.u8());
    p.elasticity = static_cast<Elasticity>(r.u8());
    const std::uint8_t collides = r.u8();
    if (r.ok() && collides > 1) return fail("primitive set: primitive {} bad collide flag", i);
    p.collides = collides == 1;
    p.bone = r.i32();
    p.shape.a = vec3(r);
    p.shape.b = vec3(r);
    p.shape.u = vec3(r);
    p.shape.v = vec3(r);
    p.shape.radius_a = r.f32();
    p.shape.radius_b = r.f32();
    p.shape.polygon_count = static_cast<int>(r.u32());
    for (glm::vec2& q : p.shape.polygon) {
      q.x = r.f32();
      q.y = r.f32();
    }
    p.r_in = r.f32();
    p.r_out = r.f32();
    p.weight = r.f32();
    p.density.knee = r.f32();
    p.density.slope = r.f32();
    p.stiffness = r.f32();
    p.time_constant = r.f32();
    SkinWeightGrid& g = p.skin_weight;
    g.n = r.u8();
    if (r.ok() && g.n != 0) {
      if (g.n < 2 || g.n > kMaxSkinWeightSamples) {
        return fail("primitive set: primitive {} skin weight grid of {} samples per axis", i, g.n);
      }
      g.box.min = vec3(r);
      g.box.max = vec3(r);
      g.values.resize(static_cast<std::size_t>(g.n * g.n * g.n));
      for (float& x : g.values) x = r.f32();
      g.max_value = *std::max_element(g.values.begin(), g.values.end());
    }
    prepareShape(p.shape);
  }
  if (Status st = finish(r, "primitive set"); !st) return st.error();
  if (Status st = validatePrimitiveSet(s, joint_count); !st) return st.error();
  return s;
}

void encodeCombinationGraph(const CombinationGraph& g, ByteWriter& w) {
  w.u32(kCombinationGraphVersion);
  w.u32(static_cast<std::uint32_t>(g.blends.size()));
  for (const Blend& b : g.blends) {
    w.u16(b.limb_a);
    w.u16(b.limb_b);
    w.u16(b.joint);
  }
  w.u32(static_cast<std::uint32_t>(g.collide_pairs.size()));
  for (const auto& p : g.collide_pairs) {
    w.u16(p[0]);
    w.u16(p[1]);
  }
}

Result<CombinationGraph> decodeCombinationGraph(std::span<const std::uint8_t> bytes,
                                                const PrimitiveSet& set) {
  ByteReader r(bytes);
  const std::uint32_t version = r.u32();
  if (r.ok() && version != kCombinationGraphVersion) {
    return fail("combination graph: version {} (this build reads {})", version,
                kCombinationGraphVersion);
  }
  CombinationGraph g;
  const std::uint32_t nb = r.u32();
  if (!r.ok() || nb > r.remaining() / 6) return fail("combination graph: bad blend count {}", nb);
  g.blends.resize(nb);
  for (Blend& b : g.blends) {
    b.limb_a = r.u16();
    b.limb_b = r.u16();
    b.joint = r.u16();
  }
  const std::uint32_t np = r.u32();
  if (!r.ok() || np > r.remaining() / 4) return fail("combination graph: bad pair count {}", np);
  g.collide_pairs.resize(np);
  for (auto& p : g.collide_pairs) {
    p[0] = r.u16();
    p[1] = r.u16();
  }
  if (Status st = finish(r, "combination graph"); !st) return st.error();
  // The stored pairs must already be canonical (encoders write finalized graphs).
  for (std::size_t i = 0; i < g.collide_pairs.size(); ++i) {
    const auto& p = g.collide_pairs[i];
    if (p[0] >= p[1] || (i > 0 && !(g.collide_pairs[i - 1] < p))) {
      return fail("combination graph: collide pair {} not in canonical order", i);
    }
  }
  finalizeGraph(g, static_cast<int>(set.items.size()));
  if (Status st = validateCombinationGraph(g, set); !st) return st.error();
  return g;
}

void encodeCalibration(const Calibration& c, ByteWriter& w) {
  w.u32(kCalibrationVersion);
  w.u32(static_cast<std::uint32_t>(c.vertex_class.size()));
  w.array(std::span<const VertexClass>(c.vertex_class));
  w.array(std::span<const std::array<std::int16_t, 4>>(c.prims));
  w.array(std::span<const float>(c.w));
  w.array(std::span<const float>(c.slope));
  w.array(std::span<const std::uint8_t>(c.rigid));
  w.u32(static_cast<std::uint32_t>(c.own_weight.size()));
  w.array(std::span<const float>(c.own_weight));
  w.u32(static_cast<std::uint32_t>(c.pairs.size()));
  w.array(std::span<const std::uint32_t>(c.pair_offsets));
  for (const VertexPair& p : c.pairs) {
    w.u16(static_cast<std::uint16_t>(p.prim));
    w.u8(p.flags);
    w.f32(p.iso);
  }
  w.u32(static_cast<std::uint32_t>(c.ring.size()));
  w.array(std::span<const std::uint32_t>(c.ring_offsets));
  w.array(std::span<const std::uint32_t>(c.ring));
  w.array(std::span<const float>(c.ring_weights));
}

Result<Calibration> decodeCalibration(std::span<const std::uint8_t> bytes, const PrimitiveSet& set,
                                      int vertex_count) {
  ByteReader r(bytes);
  const std::uint32_t version = r.u32();
  // Version 1 had no own weights: read as none (the own field is not faded).
  if (r.ok() && version != kCalibrationVersion && version != 1) {
    return fail("calibration: version {} (this build reads 1 and {})", version,
                kCalibrationVersion);
  }
  Calibration c;
  const std::uint32_t nv = r.u32();
  if (r.ok() && nv != static_cast<std::uint32_t>(vertex_count)) {
    return fail("calibration: {} vertices, the skin has {}", nv, vertex_count);
  }
  r.array(c.vertex_class, nv);
  r.array(c.prims, nv);
  r.array(c.w, nv);
  r.array(c.slope, nv);
  r.array(c.rigid, nv);
  const std::uint32_t nown = version >= 2 ? r.u32() : 0;
  if (r.ok() && nown != 0 && nown != nv) {
    return fail("calibration: {} own weights for {} vertices", nown, nv);
  }
  r.array(c.own_weight, nown);
  const std::uint32_t npairs = r.u32();
  r.array(c.pair_offsets, static_cast<std::size_t>(nv) + 1);
  if (!r.ok() || npairs > r.remaining() / 7) return fail("calibration: bad pair count {}", npairs);
  c.pairs.resize(npairs);
  for (VertexPair& p : c.pairs) {
    p.prim = static_cast<std::int16_t>(r.u16());
    p.flags = r.u8();
    p.iso = r.f32();
  }
  const std::uint32_t nring = r.u32();
  r.array(c.ring_offsets, static_cast<std::size_t>(nv) + 1);
  if (!r.ok() || nring > r.remaining() / 8) return fail("calibration: bad ring count {}", nring);
  r.array(c.ring, nring);
  r.array(c.ring_weights, nring);
  if (Status st = finish(r, "calibration"); !st) return st.error();
  if (Status st = validateCalibration(c, set, vertex_count); !st) return st.error();
  return c;
}

std::vector<std::uint8_t> encodeImplicitModel(const ImplicitModel& m) {
  std::vector<std::uint8_t> out;
  ByteWriter w(out);
  const auto section = [&](auto&& encode) {
    const std::size_t at = w.size();
    w.u32(0);
    encode();
    w.patchU32(at, static_cast<std::uint32_t>(w.size() - at - 4));
  };
  section([&] { encodePrimitiveSet(m.primitives, w); });
  section([&] { encodeCombinationGraph(m.graph, w); });
  section([&] { encodeCalibration(m.calibration, w); });
  return out;
}

Result<ImplicitModel> decodeImplicitModel(std::span<const std::uint8_t> bytes, int joint_count,
                                          int vertex_count) {
  ByteReader r(bytes);
  const auto section = [&r](std::string_view what) -> Result<std::span<const std::uint8_t>> {
    const std::uint32_t size = r.u32();
    std::span<const std::uint8_t> s = r.bytes(size);
    if (!r.ok()) return fail("implicit model: {} section truncated", what);
    return s;
  };
  ImplicitModel m;
  auto ps = section("primitive");
  if (!ps) return ps.error();
  auto set = decodePrimitiveSet(*ps, joint_count);
  if (!set) return set.error();
  m.primitives = std::move(*set);
  auto gs = section("graph");
  if (!gs) return gs.error();
  auto graph = decodeCombinationGraph(*gs, m.primitives);
  if (!graph) return graph.error();
  m.graph = std::move(*graph);
  auto cs = section("calibration");
  if (!cs) return cs.error();
  auto cal = decodeCalibration(*cs, m.primitives, vertex_count);
  if (!cal) return cal.error();
  m.calibration = std::move(*cal);
  if (r.remaining() != 0) return fail("implicit model: {} trailing bytes", r.remaining());
  return m;
}

}  // namespace vistel
