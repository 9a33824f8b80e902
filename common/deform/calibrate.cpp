// Calibration: w_v = T / D_v(P_rest) (DESIGN.md §3), rest-contact thresholds, and
// mean-value relaxation weights (Vaillant et al. 2013, after Floater's mean value
// coordinates).
#include "common/deform/calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>

#include "common/deform/posed_primitives.hpp"
#include "common/deform/vertex_field.hpp"

namespace vistel {
namespace {

// Skin vertices whose ray keys share a sample with a vertex this much farther from the
// skeleton (metres) are a deeper layer (see fitSkinWeights).
constexpr float kLayerGap = 0.005f;

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

void fitSkinWeights(ImplicitModel& model, std::span<const glm::vec3> pos, int samples) {
  const Calibration& c = model.calibration;
  std::vector<std::uint32_t> own;
  for (std::size_t i = 0; i < model.primitives.items.size(); ++i) {
    Primitive& p = model.primitives.items[i];
    SkinWeightGrid& g = p.skin_weight;
    g = SkinWeightGrid{};
    own.clear();
    for (std::uint32_t v = 0; v < c.prims.size(); ++v) {
      if (c.vertex_class[v] != VertexClass::kFree && c.prims[v][0] == static_cast<int>(i))
        own.push_back(v);
    }
    if (own.empty() || samples < 2) continue;
    const PosedPrimitive rest = posePrimitive(p, glm::mat4(1.0f));
    g.box = rest.bounds;
    g.n = std::min(samples, kMaxSkinWeightSamples);
    const int n = g.n;
    const auto cells = static_cast<Eigen::Index>(n) * n * n;
    const auto index = [n](int x, int y, int z) {
      return static_cast<Eigen::Index>((z * n + y) * n + x);
    };
    // Least squares: the trilinear interpolation reproduces w_v at every own vertex's key
    // (where its ray from the skeleton crosses the lookup shell, see skinWeightKey), and
    // neighbouring samples agree (a small membrane term that also fills samples no key is
    // near). Normal equations, solved by conjugate gradients from w = 1.
    std::vector<Eigen::Triplet<double>> terms;
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(cells);
    const glm::vec3 size = g.box.max - g.box.min;
    const float last = static_cast<float>(n - 1);
    const auto add = [&](const glm::vec3& q, double value) {
      const glm::vec3 u =
          glm::clamp((q - g.box.min) / size * last, glm::vec3(0.0f), glm::vec3(last));
      const glm::ivec3 i0 = glm::min(glm::ivec3(u), glm::ivec3(n - 2));
      const glm::vec3 t = u - glm::vec3(i0);
      Eigen::Index idx[8];
      double wt[8];
      for (int k = 0; k < 8; ++k) {
        const int dx = k & 1, dy = (k >> 1) & 1, dz = (k >> 2) & 1;
        idx[k] = index(i0.x + dx, i0.y + dy, i0.z + dz);
        wt[k] = static_cast<double>(dx != 0 ? t.x : 1.0f - t.x) * (dy != 0 ? t.y : 1.0f - t.y) *
                (dz != 0 ? t.z : 1.0f - t.z);
      }
      for (int a = 0; a < 8; ++a) {
        rhs[idx[a]] += wt[a] * value;
        for (int b = 0; b < 8; ++b) terms.emplace_back(idx[a], idx[b], wt[a] * wt[b]);
      }
    };
    // A partner meets the outermost skin on each ray: where rays of several layers share a
    // sample (lips over teeth, lids over eyes), the deeper layers are left out.
    std::vector<glm::vec3> keys(own.size());
    std::vector<float> depth(own.size());
    std::vector<float> outermost(static_cast<std::size_t>(cells), 0.0f);
    const auto nearest = [&](const glm::vec3& q) {
      const glm::ivec3 at = glm::clamp(glm::ivec3(glm::round((q - g.box.min) / size * last)),
                                       glm::ivec3(0), glm::ivec3(n - 1));
      return static_cast<std::size_t>(index(at.x, at.y, at.z));
    };
    for (std::size_t k = 0; k < own.size(); ++k) {
      float scale;
      const glm::vec3 d = skeletonOffset(rest.shape, pos[own[k]], scale);
      keys[k] = skinWeightKey(rest, pos[own[k]], d, scale);
      depth[k] = glm::length(d);  // metres
      float& o = outermost[nearest(keys[k])];
      o = std::max(o, depth[k]);
    }
    for (std::size_t k = 0; k < own.size(); ++k) {
      if (depth[k] < outermost[nearest(keys[k])] - kLayerGap) continue;
      add(keys[k], c.w[own[k]]);
    }
    const double membrane = 1e-2 * static_cast<double>(own.size()) / static_cast<double>(cells);
    for (int z = 0; z < n; ++z) {
      for (int y = 0; y < n; ++y) {
        for (int x = 0; x < n; ++x) {
          const Eigen::Index a = index(x, y, z);
          const Eigen::Index next[3] = {x + 1 < n ? index(x + 1, y, z) : -1,
                                        y + 1 < n ? index(x, y + 1, z) : -1,
                                        z + 1 < n ? index(x, y, z + 1) : -1};
          for (const Eigen::Index b : next) {
            if (b < 0) continue;
            terms.emplace_back(a, a, membrane);
            terms.emplace_back(b, b, membrane);
            terms.emplace_back(a, b, -membrane);
            terms.emplace_back(b, a, -membrane);
          }
        }
      }
    }
    Eigen::SparseMatrix<double> normal(cells, cells);
    normal.setFromTriplets(terms.begin(), terms.end());
    Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
    cg.setTolerance(1e-8);
    cg.compute(normal);
    const Eigen::VectorXd solved = cg.solveWithGuess(rhs, Eigen::VectorXd::Ones(cells));
    g.values.resize(static_cast<std::size_t>(cells));
    g.max_value = kMinSkinWeight;
    for (Eigen::Index k = 0; k < cells; ++k) {
      const double x = std::isfinite(solved[k]) ? solved[k] : 1.0;
      const float value = std::clamp(static_cast<float>(x), kMinSkinWeight, kMaxSkinWeight);
      g.values[static_cast<std::size_t>(k)] = value;
      g.max_value = std::max(g.max_value, value);
    }
  }
}

Result<CalibrationReport> calibrateModel(ImplicitModel& model, std::span<const glm::vec3> pos,
                                         std::span<const glm::vec3> nrm,
                                         const FieldCalibrationOptions& opt) {
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
  }
  // The skins' weights around their primitives, then the rest contacts measured against
  // them (a partner meets a primitive's skin where w_i F_i = T).
  fitSkinWeights(model, pos);
  for (std::size_t i = 0; i < np; ++i) rest.items[i] = posePrimitive(set.items[i], glm::mat4(1.0f));
  for (std::size_t v = 0; v < nv; ++v) {
    const auto& pr = c.prims[v];
    const VertexClass cls = c.vertex_class[v];
    // Rest contacts with same-body primitives that collide with the vertex's own ones.
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
      // The partner's skin weight, or the own one for a neighbouring part (as in Step 2).
      bool neighbour = false;
      for (int k = 0; k < owners; ++k) {
        const std::int16_t o = pr[static_cast<std::size_t>(k)];
        if (o >= 0 && model.graph.neighbours(o, static_cast<int>(i))) neighbour = true;
      }
      const float omega = std::isinf(set.items[i].stiffness)
                              ? 1.0f
                              : (neighbour ? c.w[v] : skinWeight(rest.items[i], pos[v]));
      const float x = omega * primitiveField(rest.items[i], pos[v]);
      if (x > iso * (1.0f - opt.rest_margin)) {
        // At least the set's iso (which the file's validation asks), whatever the rounding.
        c.pairs.push_back({ii, 0, std::max(iso, x + iso * opt.rest_margin)});
        ++report.rest_pairs;
      }
    }
    // A joint vertex also collides with its opposite limb, from its rest value on, scaled
    // by its own weight (the crease between adjacent limbs is calibrated at rest, where
    // the two skins are one).
    if (cls == VertexClass::kJoint) {
      const auto opp = static_cast<std::size_t>(pr[2]);
      const float omega = std::isinf(set.items[opp].stiffness) ? 1.0f : c.w[v];
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
