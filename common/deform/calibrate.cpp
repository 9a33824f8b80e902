// Calibration: w_v = T / D_v(P_rest) (DESIGN.md §3), rest-contact thresholds, and
// mean-value relaxation weights (Vaillant et al. 2013, after Floater's mean value
// coordinates).
#include "common/deform/calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/deform/posed_primitives.hpp"
#include "common/deform/vertex_field.hpp"

namespace vistel {
namespace {

// Field slope at a primitive's surface (per metre), for free vertices it owns.
float surfaceSlope(const PrimitiveSet& set, const PosedPrimitive& p, const Primitive& q) {
  float fp = 0.0f;
  const float d_in = q.r_in / q.r_out;
  const float f = densityValue(q.density, d_in, &fp);
  const float reach = std::max(p.reach, 1e-4f);
  const float slope = f > 0.0f ? set.iso * std::abs(fp) / (f * reach) : 0.0f;
  return slope > 0.0f && std::isfinite(slope) ? slope : 50.0f;
}

}  // namespace

Result<CalibrationReport> calibrateModel(ImplicitModel& model, std::span<const glm::vec3> pos,
                                         std::span<const glm::vec3> nrm,
                                         const CalibrationOptions& opt) {
  Calibration& c = model.calibration;
  const PrimitiveSet& set = model.primitives;
  const std::size_t nv = pos.size();
  if (nrm.size() != nv || c.vertex_class.size() != nv || c.prims.size() != nv) {
    return fail("calibration: {} positions, {} normals, {} classes, {} prim sets disagree", nv,
                nrm.size(), c.vertex_class.size(), c.prims.size());
  }
  const std::size_t np = set.items.size();
  if (model.graph.primitive_count != static_cast<int>(np)) {
    return fail("calibration: graph not finalized for {} primitives", np);
  }
  // The primitives at rest.
  PosedPrimitives rest;
  rest.items.resize(np);
  for (std::size_t i = 0; i < np; ++i) rest.items[i] = posePrimitive(set.items[i], glm::mat4(1.0f));

  const float iso = set.iso;
  CalibrationReport report;
  c.w.assign(nv, 1.0f);
  c.slope.assign(nv, 0.0f);
  if (c.rigid.size() != nv) c.rigid.assign(nv, 0);
  c.pairs.clear();
  c.pair_offsets.assign(nv + 1, 0);
  if (c.ring_offsets.size() != nv + 1) {
    c.ring_offsets.assign(nv + 1, 0);
    c.ring.clear();
    c.ring_weights.clear();
  }
  for (std::size_t v = 0; v < nv; ++v) {
    auto& pr = c.prims[v];
    for (const std::int16_t p : pr) {
      if (p != kNoPrimitive && (p < 0 || static_cast<std::size_t>(p) >= np)) {
        return fail("calibration: vertex {} names primitive {} of {}", v, p, np);
      }
    }
    // Weight w_v, or demotion to a free vertex when the own field is too weak at rest.
    if (c.vertex_class[v] != VertexClass::kFree) {
      if (pr[0] < 0 || (c.vertex_class[v] == VertexClass::kJoint && (pr[1] < 0 || pr[2] < 0))) {
        return fail("calibration: vertex {} lacks its defining primitives", v);
      }
      const float d = vertexDensity(model, rest, static_cast<int>(v), pos[v]);
      if (d >= iso * opt.min_density && std::isfinite(d)) {
        c.w[v] = iso / d;
      } else {
        c.vertex_class[v] = VertexClass::kFree;
        pr[1] = pr[2] = pr[3] = kNoPrimitive;
        c.rigid[v] = 0;
        ++report.demoted;
      }
    }
    const VertexClass cls = c.vertex_class[v];
    if (cls == VertexClass::kFree) {
      c.w[v] = 1.0f;
      c.slope[v] = pr[0] >= 0 ? surfaceSlope(set, rest.items[static_cast<std::size_t>(pr[0])],
                                             set.items[static_cast<std::size_t>(pr[0])])
                              : 50.0f;
      ++report.free;
    } else if (cls == VertexClass::kJoint) {
      ++report.joint;
    } else {
      ++report.limb;
    }
    // Rest contacts with same-body primitives that collide with the vertex's own ones.
    const float w = c.w[v];
    const int owners = cls == VertexClass::kJoint ? 3 : 1;
    for (std::size_t i = 0; i < np; ++i) {
      const auto ii = static_cast<std::int16_t>(i);
      if (!set.items[i].collides || ii == pr[0] || ii == pr[1] || ii == pr[2] || ii == pr[3]) {
        continue;
      }
      bool collides = false;
      for (int k = 0; k < owners; ++k) {
        const std::int16_t o = pr[static_cast<std::size_t>(k)];
        if (o >= 0 && model.graph.collides(o, static_cast<int>(i))) collides = true;
      }
      if (!collides) continue;
      const float omega = std::isinf(set.items[i].stiffness) ? 1.0f : w;
      const float x = omega * primitiveField(rest.items[i], pos[v]);
      if (x > iso * (1.0f - opt.rest_margin)) {
        c.pairs.push_back({ii, 0, x + iso * opt.rest_margin});
        ++report.rest_pairs;
      }
    }
    // A joint vertex also collides with its opposite limb, from its rest value on.
    if (cls == VertexClass::kJoint) {
      const auto opp = static_cast<std::size_t>(pr[2]);
      const float omega = std::isinf(set.items[opp].stiffness) ? 1.0f : w;
      const float x = omega * primitiveField(rest.items[opp], pos[v]);
      c.pairs.push_back({pr[2], kPairAlways, std::max(iso, x + iso * opt.always_margin)});
    }
    c.pair_offsets[v + 1] = static_cast<std::uint32_t>(c.pairs.size());
  }
  return report;
}

void computeRelaxationWeights(std::span<const glm::vec3> pos, std::span<const glm::vec3> nrm,
                              std::span<const std::uint32_t> indices, Calibration& c) {
  const std::size_t nv = pos.size();
  // Vertex -> incident faces.
  std::vector<std::uint32_t> off(nv + 1, 0);
  for (const std::uint32_t i : indices) ++off[i + 1];
  for (std::size_t v = 0; v < nv; ++v) off[v + 1] += off[v];
  std::vector<std::uint32_t> faces(indices.size());
  std::vector<std::uint32_t> fill(off.begin(), off.end() - 1);
  for (std::size_t i = 0; i < indices.size(); ++i)
    faces[fill[indices[i]]++] = static_cast<std::uint32_t>(i / 3);

  c.ring_offsets.assign(nv + 1, 0);
  c.ring.clear();
  c.ring_weights.clear();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;  // (next, prev) around v
  std::vector<std::uint32_t> ordered;
  std::vector<float> weights;
  for (std::size_t v = 0; v < nv; ++v) {
    // The ring's directed edges: in face (v, a, b) counter-clockwise, a -> b.
    edges.clear();
    for (std::uint32_t k = off[v]; k < off[v + 1]; ++k) {
      const std::size_t f = 3u * faces[k];
      for (int j = 0; j < 3; ++j) {
        if (indices[f + static_cast<std::size_t>(j)] == v) {
          edges.emplace_back(indices[f + static_cast<std::size_t>((j + 1) % 3)],
                             indices[f + static_cast<std::size_t>((j + 2) % 3)]);
        }
      }
    }
    // Walk the edges into a cycle (a closed manifold fan).
    ordered.clear();
    bool closed = !edges.empty();
    if (closed) {
      std::uint32_t cur = edges[0].first;
      for (std::size_t step = 0; step < edges.size() && closed; ++step) {
        ordered.push_back(cur);
        const auto it = std::find_if(edges.begin(), edges.end(),
                                     [cur](const auto& e) { return e.first == cur; });
        if (it == edges.end()) {
          closed = false;
        } else {
          cur = it->second;
        }
      }
      closed = closed && cur == edges[0].first;
      if (closed) {
        std::vector<std::uint32_t> sorted = ordered;
        std::sort(sorted.begin(), sorted.end());
        closed = std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
      }
    }
    // Mean value coordinates in the tangent plane, or uniform weights.
    weights.clear();
    bool mvc = closed && ordered.size() >= 3;
    const glm::vec3 n = glm::length(nrm[v]) > 0.0f ? glm::normalize(nrm[v]) : glm::vec3(0, 1, 0);
    if (mvc) {
      const std::size_t m = ordered.size();
      std::vector<glm::vec3> q(m);
      std::vector<float> r(m);
      for (std::size_t j = 0; j < m; ++j) {
        glm::vec3 d = pos[ordered[j]] - pos[v];
        d -= glm::dot(d, n) * n;
        q[j] = d;
        r[j] = glm::length(d);
        if (!(r[j] > 1e-9f)) mvc = false;
      }
      float total_angle = 0.0f;
      std::vector<float> half_tan(m);
      for (std::size_t j = 0; mvc && j < m; ++j) {
        const glm::vec3& a = q[j];
        const glm::vec3& b = q[(j + 1) % m];
        const float sinv = glm::dot(glm::cross(a, b), n);
        const float cosv = glm::dot(a, b);
        const float ang = std::atan2(sinv, cosv);
        if (!(ang > 0.0f)) mvc = false;  // not star-shaped around v
        total_angle += ang;
        half_tan[j] = std::tan(0.5f * ang);
      }
      if (mvc && std::abs(total_angle - 2.0f * std::numbers::pi_v<float>) > 1e-2f) mvc = false;
      if (mvc) {
        float sum = 0.0f;
        for (std::size_t j = 0; j < m; ++j) {
          const float wj = (half_tan[(j + m - 1) % m] + half_tan[j]) / r[j];
          weights.push_back(wj);
          sum += wj;
        }
        for (float& wj : weights) wj /= sum;
      }
    }
    if (!mvc) {
      // Unique neighbours, uniform.
      ordered.clear();
      for (const auto& e : edges) {
        ordered.push_back(e.first);
        ordered.push_back(e.second);
      }
      std::sort(ordered.begin(), ordered.end());
      ordered.erase(std::unique(ordered.begin(), ordered.end()), ordered.end());
      weights.assign(ordered.size(),
                     ordered.empty() ? 0.0f : 1.0f / static_cast<float>(ordered.size()));
    }
    c.ring.insert(c.ring.end(), ordered.begin(), ordered.end());
    c.ring_weights.insert(c.ring_weights.end(), weights.begin(), weights.end());
    c.ring_offsets[v + 1] = static_cast<std::uint32_t>(c.ring.size());
  }
}

}  // namespace vistel
