#include "offline/synthesize/seam_loft.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vistel {
namespace {

// A rim walked in a chosen sense, with arc-length parameters in [0, 1).
struct Rim {
  std::vector<std::uint32_t> order;  // entries of the curve
  std::vector<float> u;              // per entry of `order`; u[0] = 0
  glm::vec3 centroid{0.0f};
  float length = 0.0f;
};

Rim makeRim(const RimCurve& curve, bool reverse) {
  Rim rim;
  const std::size_t n = curve.index.size();
  for (std::size_t i = 0; i < n; ++i) {
    rim.order.push_back(static_cast<std::uint32_t>(reverse ? n - 1 - i : i));
  }
  rim.u.resize(n);
  float run = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    rim.u[i] = run;
    const glm::vec3& p = curve.position[rim.order[i]];
    rim.centroid += p;
    run += glm::distance(p, curve.position[rim.order[(i + 1) % n]]);
  }
  rim.length = run;
  rim.centroid /= static_cast<float>(n);
  for (float& u : rim.u) u = run > 0.0f ? u / run : 0.0f;
  return rim;
}

float wrap01(float u) { return u - std::floor(u); }

// The rim point at parameter u (wrapped into [0, 1)).
RimPoint rimPoint(const Rim& rim, float u) {
  u = wrap01(u);
  const std::size_t n = rim.order.size();
  const auto it = std::upper_bound(rim.u.begin(), rim.u.end(), u);
  const std::size_t k = static_cast<std::size_t>(it - rim.u.begin()) - 1;  // u[0] = 0 <= u
  const float u0 = rim.u[k];
  const float u1 = k + 1 < n ? rim.u[k + 1] : 1.0f;
  RimPoint p;
  p.a = rim.order[k];
  p.b = rim.order[(k + 1) % n];
  p.t = u1 > u0 ? std::clamp((u - u0) / (u1 - u0), 0.0f, 1.0f) : 0.0f;
  return p;
}

glm::vec3 position(const RimCurve& curve, const RimPoint& p) {
  return glm::mix(curve.position[p.a], curve.position[p.b], p.t);
}

glm::vec3 normal(const RimCurve& curve, const RimPoint& p) {
  const glm::vec3 n = glm::mix(curve.normal[p.a], curve.normal[p.b], p.t);
  const float len = glm::length(n);
  return len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
}

// The shift of the child's parameter that best lays its centred shape onto the parent's,
// tried at 4N evenly spaced values.
float bestShift(const RimCurve& pc, const Rim& parent, const RimCurve& cc, const Rim& child,
                int n) {
  std::vector<glm::vec3> p(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    p[static_cast<std::size_t>(i)] =
        position(pc, rimPoint(parent, static_cast<float>(i) / static_cast<float>(n))) -
        parent.centroid;
  }
  const int tries = 4 * n;
  float best = 0.0f, best_cost = std::numeric_limits<float>::max();
  for (int k = 0; k < tries; ++k) {
    const float shift = static_cast<float>(k) / static_cast<float>(tries);
    float cost = 0.0f;
    for (int i = 0; i < n && cost < best_cost; ++i) {
      const float u = static_cast<float>(i) / static_cast<float>(n) + shift;
      const glm::vec3 q = position(cc, rimPoint(child, u)) - child.centroid;
      const glm::vec3 d = q - p[static_cast<std::size_t>(i)];
      cost += glm::dot(d, d);
    }
    if (cost < best_cost) {
      best_cost = cost;
      best = shift;
    }
  }
  return best;
}

// One closed row of vertices for zipping: output indices, positions and parameters, in
// the common sense.
struct Row {
  std::vector<std::uint32_t> index;
  std::vector<glm::vec3> position;
  std::vector<float> u;
};

// Starts a row at its smallest parameter.
Row rotated(const Row& row) {
  const std::size_t start =
      static_cast<std::size_t>(std::min_element(row.u.begin(), row.u.end()) - row.u.begin());
  Row out;
  for (std::size_t k = 0; k < row.u.size(); ++k) {
    const std::size_t i = (start + k) % row.u.size();
    out.index.push_back(row.index[i]);
    out.position.push_back(row.position[i]);
    out.u.push_back(row.u[i]);
  }
  return out;
}

// Triangles between row p (the parent's side) and row q (the child's side), both in the
// common sense: from the diagonal p_i q_j, advancing p gives (p_i, q_j, p_i+1), advancing
// q gives (q_j, q_j+1, p_i); the row whose next parameter is smaller advances. Every edge of either
// row is used once, run p_i+1 -> p_i and q_j -> q_j+1.
void zipRows(const Row& p_in, const Row& q_in, std::vector<std::uint32_t>& out) {
  const Row p = rotated(p_in);
  const Row q = rotated(q_in);
  const std::size_t np = p.index.size(), nq = q.index.size();
  std::size_t i = 0, j = 0;
  while (i < np || j < nq) {
    const std::size_t pi = i % np, pn = (i + 1) % np;
    const std::size_t qj = j % nq, qn = (j + 1) % nq;
    // The row whose next vertex comes first along the common parameter advances.
    bool advance_p;
    if (i == np) {
      advance_p = false;
    } else if (j == nq) {
      advance_p = true;
    } else {
      const float up = i + 1 < np ? p.u[i + 1] : 1.0f + p.u[0];
      const float uq = j + 1 < nq ? q.u[j + 1] : 1.0f + q.u[0];
      advance_p = up <= uq;
    }
    if (advance_p) {
      out.insert(out.end(), {p.index[pi], q.index[qj], p.index[pn]});
      ++i;
    } else {
      out.insert(out.end(), {q.index[qj], q.index[qn], p.index[pi]});
      ++j;
    }
  }
}

// Cubic Hermite basis at s.
glm::vec3 hermite(const glm::vec3& p0, const glm::vec3& m0, const glm::vec3& p1,
                  const glm::vec3& m1, float s) {
  const float s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 +
         (s3 - s2) * m1;
}

// The part of d in the plane of unit normal n, as long as d.
glm::vec3 alongSurface(const glm::vec3& d, const glm::vec3& n) {
  const glm::vec3 t = d - glm::dot(d, n) * n;
  const float len = glm::length(t);
  return len > 1e-9f ? t * (glm::length(d) / len) : d;
}

}  // namespace

SeamLoft loftSeam(const LoftSide& parent, const LoftSide& child, std::uint32_t first_new_vertex,
                  const LoftOptions& options) {
  SeamLoft loft;
  // Both rims in the sense of the parent's triangles (the child's runs the other way).
  const RimCurve& pc = *parent.rim;
  const RimCurve& cc = *child.rim;
  const Rim rp = makeRim(pc, false);
  const Rim rc = makeRim(cc, true);
  const int n = static_cast<int>(std::max(rp.order.size(), rc.order.size()));
  const float shift = bestShift(pc, rp, cc, rc, n);
  const float spacing =
      options.ring_spacing_m > 0.0f
          ? options.ring_spacing_m
          : (rp.length + rc.length) / static_cast<float>(rp.order.size() + rc.order.size());

  // The rim points each ring parameter runs between, and the region's length.
  std::vector<RimPoint> at_p(static_cast<std::size_t>(n)), at_c(static_cast<std::size_t>(n));
  float length = 0.0f;
  for (int i = 0; i < n; ++i) {
    const float u = static_cast<float>(i) / static_cast<float>(n);
    at_p[static_cast<std::size_t>(i)] = rimPoint(rp, u);
    at_c[static_cast<std::size_t>(i)] = rimPoint(rc, u + shift);
    length += glm::distance(position(pc, at_p[static_cast<std::size_t>(i)]),
                            position(cc, at_c[static_cast<std::size_t>(i)]));
  }
  loft.length = length / static_cast<float>(n);
  const int rings = std::max(0, static_cast<int>(std::lround(loft.length / spacing)) - 1);
  loft.rings = rings;
  loft.ring_size = n;

  // Ring vertices: on the Hermite curves, then onto the blended field.
  const float max_step = 0.5f * std::max(spacing, loft.length / static_cast<float>(rings + 1));
  for (int k = 1; k <= rings; ++k) {
    const float s = static_cast<float>(k) / static_cast<float>(rings + 1);
    const float w = s * s * (3.0f - 2.0f * s);
    for (int i = 0; i < n; ++i) {
      const RimPoint& a = at_p[static_cast<std::size_t>(i)];
      const RimPoint& b = at_c[static_cast<std::size_t>(i)];
      const glm::vec3 p0 = position(pc, a);
      const glm::vec3 p1 = position(cc, b);
      const glm::vec3 d = p1 - p0;
      glm::vec3 x =
          hermite(p0, alongSurface(d, normal(pc, a)), p1, alongSurface(d, normal(cc, b)), s);
      const glm::vec3 start = x;
      for (int step = 0; step < options.newton_steps; ++step) {
        const FieldSample fp = parent.field->at(x);
        const FieldSample fc = child.field->at(x);
        const float f = (1.0f - w) * fp.value + w * fc.value;
        const glm::vec3 g = (1.0f - w) * fp.normal + w * fc.normal;
        const float gg = glm::dot(g, g);
        if (gg < 1e-6f) break;
        glm::vec3 move = (f / gg) * g;
        const float len = glm::length(move);
        if (len > max_step) move *= max_step / len;
        x -= move;
        if (len < 1e-6f) break;
      }
      loft.max_projection = std::max(loft.max_projection, glm::distance(x, start));
      loft.positions.push_back(x);
      loft.s.push_back(s);
      loft.parent_at.push_back(a);
      loft.child_at.push_back(b);
    }
  }

  // Rows: the parent's rim, the rings, the child's rim (its parameter turned by the shift).
  std::vector<Row> rows;
  Row first;
  for (std::size_t i = 0; i < rp.order.size(); ++i) {
    first.index.push_back(pc.index[rp.order[i]]);
    first.position.push_back(pc.position[rp.order[i]]);
    first.u.push_back(rp.u[i]);
  }
  rows.push_back(std::move(first));
  for (int k = 0; k < rings; ++k) {
    Row ring;
    for (int i = 0; i < n; ++i) {
      const std::size_t v = static_cast<std::size_t>(k * n + i);
      ring.index.push_back(first_new_vertex + static_cast<std::uint32_t>(v));
      ring.position.push_back(loft.positions[v]);
      ring.u.push_back(static_cast<float>(i) / static_cast<float>(n));
    }
    rows.push_back(std::move(ring));
  }
  Row last;
  for (std::size_t i = 0; i < rc.order.size(); ++i) {
    last.index.push_back(cc.index[rc.order[i]]);
    last.position.push_back(cc.position[rc.order[i]]);
    last.u.push_back(wrap01(rc.u[i] - shift));
  }
  rows.push_back(std::move(last));
  for (std::size_t r = 0; r + 1 < rows.size(); ++r) zipRows(rows[r], rows[r + 1], loft.indices);
  return loft;
}

}  // namespace vistel
