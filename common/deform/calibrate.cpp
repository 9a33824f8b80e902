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

// Weighted least-squares rounds of a skin weight grid, and how far (metres) a vertex may
// stay outside the skin surface it fits (see fitSkinWeights).
constexpr int kEnclosingRounds = 4;
constexpr float kEnclosingTolerance = 0.001f;

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

namespace {

// fitSkinWeights, where a primitive also fits the vertices that name it in also_fits (nvert,
// or empty): adopted vertices it fitted before they got a primitive of their own (see
// offline/build/free_vertex_adoption.hpp), so its skin stays where it was.
void fitSkinWeightsWith(ImplicitModel& model, std::span<const glm::vec3> pos,
                        std::span<const std::uint8_t> demoted,
                        std::span<const std::int16_t> also_fits, int samples,
                        std::span<const std::uint8_t> keep_grids = {}) {
  const Calibration& c = model.calibration;
  std::vector<std::uint32_t> own;
  std::vector<float> target;  // (own) the weight each own vertex asks for
  std::vector<float> enough;  // (own) the least weight that keeps a partner out of it
  for (std::size_t i = 0; i < model.primitives.items.size(); ++i) {
    Primitive& p = model.primitives.items[i];
    SkinWeightGrid& g = p.skin_weight;
    if (i < keep_grids.size() && keep_grids[i] != 0) continue;
    g = SkinWeightGrid{};
    // The vertices the primitive defines (limb and joint vertices, and those demoted for a
    // weak field at rest, which still move with it), each with the weight that puts this
    // primitive's own iso-surface through it: w = T / F_i(P_rest) (a joint or bone vertex's
    // w_v calibrates the sum D_v, not F_i alone), at most kMaxSkinWeight. Other free vertices
    // (fingers, toes) move with bones the primitive does not follow.
    const PosedPrimitive rest = posePrimitive(p, glm::mat4(1.0f));
    own.clear();
    target.clear();
    enough.clear();
    for (std::uint32_t v = 0; v < c.prims.size(); ++v) {
      const bool also = v < also_fits.size() && also_fits[v] == static_cast<int>(i);
      if (c.prims[v][0] != static_cast<int>(i) && !also) continue;
      if (!also && c.vertex_class[v] == VertexClass::kFree &&
          (v >= demoted.size() || demoted[v] == 0))
        continue;
      const float f = primitiveField(rest, pos[v]);
      if (!(f > 0.0f)) continue;
      own.push_back(v);
      target.push_back(std::min(model.primitives.iso / f, kMaxSkinWeight));
      // The weight that leaves the vertex kEnclosingTolerance outside the skin surface.
      float scale;
      const glm::vec3 d = skeletonOffset(rest.shape, pos[v], scale);
      const float len = glm::length(d);
      const glm::vec3 deeper =
          len > kEnclosingTolerance ? pos[v] - (kEnclosingTolerance / len) * d : pos[v];
      enough.push_back(
          std::min(model.primitives.iso / primitiveField(rest, deeper), target.back()));
    }
    if (own.empty() || samples < 2) continue;
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
    // The eight samples around bind-space point q and their trilinear weights.
    const auto corners = [&](const glm::vec3& q, Eigen::Index* idx, double* wt) {
      const glm::vec3 u =
          glm::clamp((q - g.box.min) / size * last, glm::vec3(0.0f), glm::vec3(last));
      const glm::ivec3 i0 = glm::min(glm::ivec3(u), glm::ivec3(n - 2));
      const glm::vec3 t = u - glm::vec3(i0);
      for (int k = 0; k < 8; ++k) {
        const int dx = k & 1, dy = (k >> 1) & 1, dz = (k >> 2) & 1;
        idx[k] = index(i0.x + dx, i0.y + dy, i0.z + dz);
        wt[k] = static_cast<double>(dx != 0 ? t.x : 1.0f - t.x) * (dy != 0 ? t.y : 1.0f - t.y) *
                (dz != 0 ? t.z : 1.0f - t.z);
      }
    };
    const auto add = [&](const glm::vec3& q, double value, double weight) {
      Eigen::Index idx[8];
      double wt[8];
      corners(q, idx, wt);
      for (int a = 0; a < 8; ++a) {
        rhs[idx[a]] += weight * wt[a] * value;
        for (int b = 0; b < 8; ++b) terms.emplace_back(idx[a], idx[b], weight * wt[a] * wt[b]);
      }
    };
    const auto interpolate = [&](const Eigen::VectorXd& x, const glm::vec3& q) {
      Eigen::Index idx[8];
      double wt[8];
      corners(q, idx, wt);
      double sum = 0.0;
      for (int a = 0; a < 8; ++a) sum += wt[a] * x[idx[a]];
      return sum;
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
    std::vector<double> fit_weight(own.size());  // (own) each vertex's least-squares weight
    for (std::size_t k = 0; k < own.size(); ++k) {
      fit_weight[k] = depth[k] < outermost[nearest(keys[k])] - kLayerGap ? 0.0 : 1.0;
    }
    const double membrane = 1e-2 * static_cast<double>(own.size()) / static_cast<double>(cells);
    // Rounds of weighted least squares, each weighing more the vertices the last one left
    // outside the skin surface (w short of theirs), so the fit leans towards enclosing the
    // skin without lifting it everywhere.
    Eigen::VectorXd solved = Eigen::VectorXd::Ones(cells);
    for (int round = 0; round < kEnclosingRounds; ++round) {
      terms.clear();
      rhs.setZero();
      for (std::size_t k = 0; k < own.size(); ++k) {
        if (fit_weight[k] > 0.0) add(keys[k], target[k], fit_weight[k]);
      }
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
      solved = cg.solveWithGuess(rhs, solved);
      for (std::size_t k = 0; k < own.size(); ++k) {
        if (interpolate(solved, keys[k]) < static_cast<double>(enough[k])) {
          fit_weight[k] = std::max(fit_weight[k], 1.0) * 4.0;
        }
      }
    }
    g.values.resize(static_cast<std::size_t>(cells));
    for (Eigen::Index k = 0; k < cells; ++k) {
      const double x = std::isfinite(solved[k]) ? solved[k] : 1.0;
      g.values[static_cast<std::size_t>(k)] = std::max(static_cast<float>(x), kMinSkinWeight);
    }
    // The least-squares skin passes through the vertices on average; a partner (a rigid
    // ball) must not sink into any of them: raise the samples around each key whose
    // interpolated weight falls short of its vertex's, by the least change (along the
    // trilinear weights) that makes it exact. Raising only ever lifts the others, so one
    // pass leaves every vertex on or inside the skin surface (up to the upper clamp). A
    // deeper layer asks for less than the skin above it, so it changes nothing here.
    for (std::size_t k = 0; k < own.size(); ++k) {
      const float deficit = enough[k] - skinWeightAt(g, keys[k]);
      if (!(deficit > 0.0f)) continue;
      Eigen::Index idx[8];
      double wt[8];
      corners(keys[k], idx, wt);
      double norm2 = 0.0;
      for (const double x : wt) norm2 += x * x;
      if (!(norm2 > 0.0)) continue;
      for (int a = 0; a < 8; ++a) {
        g.values[static_cast<std::size_t>(idx[a])] +=
            static_cast<float>(static_cast<double>(deficit) * wt[a] / norm2) * 1.0001f;
      }
    }
    g.max_value = kMinSkinWeight;
    for (float& value : g.values) {
      value = std::clamp(value, kMinSkinWeight, kMaxSkinWeight);
      g.max_value = std::max(g.max_value, value);
    }
  }
}

}  // namespace

void fitSkinWeights(ImplicitModel& model, std::span<const glm::vec3> pos,
                    std::span<const std::uint8_t> demoted, int samples) {
  fitSkinWeightsWith(model, pos, demoted, {}, samples);
}

namespace {

// calibrateModel, with the skin weights fitted by fitSkinWeightsWith(also_fits).
Result<CalibrationReport> calibrateWith(ImplicitModel& model, std::span<const glm::vec3> pos,
                                        std::span<const glm::vec3> nrm,
                                        const FieldCalibrationOptions& opt,
                                        std::span<const std::int16_t> also_fits,
                                        std::span<const std::uint8_t> keep_grids) {
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
  std::vector<std::uint8_t> demoted(nv, 0);  // (nvert) made free for a weak field at rest
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
        demoted[v] = 1;
        ++report.demoted;
      }
    }
    const VertexClass cls = c.vertex_class[v];
    if (c.rigid[v] == kRigidInner) ++report.inner;
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
  fitSkinWeightsWith(model, pos, demoted, also_fits, 16, keep_grids);
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

}  // namespace

Result<CalibrationReport> calibrateModel(ImplicitModel& model, std::span<const glm::vec3> pos,
                                         std::span<const glm::vec3> nrm,
                                         const FieldCalibrationOptions& opt,
                                         std::span<const std::int16_t> also_fits,
                                         std::span<const std::uint8_t> keep_grids) {
  return calibrateWith(model, pos, nrm, opt, also_fits, keep_grids);
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
