// Inner layers of a skin mesh (see inner_layers.hpp): connected components over triangles and
// shared positions, then ray parity of each smaller component's vertices against the
// components around it, through a 2-D grid of each container's triangles per axis.
#include "common/deform/inner_layers.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numeric>

#include "common/anim/seam_copies.hpp"
#include "common/base/disjoint_sets.hpp"

namespace vistel {
namespace {

// The own-field slope given to an inner vertex where the slope array is sized (any positive
// value: a free vertex with no collider never evaluates it); calibrateModel's for a free
// vertex without an owner.
constexpr float kInnerSlope = 50.0f;

// Rays, of six, that must cross a container an odd number of times for a point to be inside.
constexpr int kInsideVotes = 4;

// Grid cells per side of a container's 2-D grid: about two triangles per cell, at most this.
constexpr int kMaxGridSide = 128;

// The side of p from the directed 2-D edge a -> b: +1 left, -1 right, never 0. The sign is
// computed for the edge's canonical direction (lexicographically smaller end first) and
// flipped, so two triangles sharing an edge see exactly opposite values; a point on the line
// is decided as if moved by (e, e^2) for an infinitesimal e (simulation of simplicity), so a
// ray through an edge or a vertex of a closed surface crosses it once.
int edgeSide(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& p) {
  const bool flip = b.x < a.x || (b.x == a.x && b.y < a.y);
  const glm::dvec2 s = flip ? b : a;
  const glm::dvec2 t = flip ? a : b;
  const double o = (t.x - s.x) * (p.y - s.y) - (t.y - s.y) * (p.x - s.x);
  int sign = 0;
  if (o != 0.0) {
    sign = o > 0.0 ? 1 : -1;
  } else if (t.y != s.y) {
    sign = t.y < s.y ? 1 : -1;  // the e term: -(t.y - s.y) e
  } else {
    sign = t.x > s.x ? 1 : -1;  // the e^2 term: (t.x - s.x) e^2
  }
  return flip ? -sign : sign;
}

double orient(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// One component's triangles projected along an axis into a grid of cells over its box, for
// rays parallel to that axis.
class AxisGrid {
 public:
  AxisGrid(int axis, std::span<const std::uint32_t> tris, std::span<const glm::vec3> pos,
           std::span<const std::uint32_t> idx, const Bounds& box)
      : axis_(axis), u_((axis + 1) % 3), v_((axis + 2) % 3), pos_(pos), idx_(idx) {
    const double side = std::sqrt(static_cast<double>(tris.size()) / 2.0);
    n_ = std::clamp(static_cast<int>(side), 1, kMaxGridSide);
    lo_ = {box.min[u_], box.min[v_]};
    const glm::dvec2 hi{box.max[u_], box.max[v_]};
    const glm::dvec2 extent = glm::max(hi - lo_, glm::dvec2(1e-9));
    scale_ = glm::dvec2(n_) / extent;
    // Each triangle in the cells its 2-D box covers (count, then fill).
    const auto cells = static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_);
    offsets_.assign(cells + 1, 0);
    const auto span_of = [&](std::uint32_t t, glm::ivec2& c0, glm::ivec2& c1) {
      glm::dvec2 mn(INFINITY), mx(-INFINITY);
      for (int k = 0; k < 3; ++k) {
        const glm::dvec2 q =
            at(idx_[3 * static_cast<std::size_t>(t) + static_cast<std::size_t>(k)]);
        mn = glm::min(mn, q);
        mx = glm::max(mx, q);
      }
      c0 = cellOf(mn);
      c1 = cellOf(mx);
    };
    for (const std::uint32_t t : tris) {
      glm::ivec2 c0, c1;
      span_of(t, c0, c1);
      for (int y = c0.y; y <= c1.y; ++y) {
        for (int x = c0.x; x <= c1.x; ++x) ++offsets_[cellIndex(x, y) + 1];
      }
    }
    for (std::size_t c = 0; c < cells; ++c) offsets_[c + 1] += offsets_[c];
    items_.resize(offsets_[cells]);
    std::vector<std::uint32_t> fill(offsets_.begin(), offsets_.end() - 1);
    for (const std::uint32_t t : tris) {
      glm::ivec2 c0, c1;
      span_of(t, c0, c1);
      for (int y = c0.y; y <= c1.y; ++y) {
        for (int x = c0.x; x <= c1.x; ++x) items_[fill[cellIndex(x, y)]++] = t;
      }
    }
  }

  // How many triangles the rays from p along +axis and -axis cross: odd bits in (above,
  // below). A crossing at p itself counts for neither.
  std::array<int, 2> crossings(const glm::vec3& p) const {
    const glm::dvec2 q{p[u_], p[v_]};
    std::array<int, 2> n{0, 0};
    const glm::ivec2 c = cellOf(q);
    const std::size_t cell = cellIndex(c.x, c.y);
    for (std::uint32_t k = offsets_[cell]; k < offsets_[cell + 1]; ++k) {
      const std::size_t f = 3 * static_cast<std::size_t>(items_[k]);
      const glm::dvec2 a = at(idx_[f]), b = at(idx_[f + 1]), d = at(idx_[f + 2]);
      const double area = orient(a, b, d);
      if (area == 0.0) continue;  // edge-on to the rays
      const int want = area > 0.0 ? 1 : -1;
      if (edgeSide(a, b, q) != want || edgeSide(b, d, q) != want || edgeSide(d, a, q) != want) {
        continue;
      }
      // Where the ray meets the triangle's plane: barycentric weights in the projection.
      const double la = orient(b, d, q) / area, lb = orient(d, a, q) / area;
      const double h = la * pos_[idx_[f]][axis_] + lb * pos_[idx_[f + 1]][axis_] +
                       (1.0 - la - lb) * pos_[idx_[f + 2]][axis_];
      const double z = p[axis_];
      if (h > z) ++n[0];
      if (h < z) ++n[1];
    }
    return n;
  }

 private:
  glm::dvec2 at(std::uint32_t v) const { return {pos_[v][u_], pos_[v][v_]}; }
  glm::ivec2 cellOf(const glm::dvec2& q) const {
    const glm::dvec2 c = glm::floor((q - lo_) * scale_);
    return glm::clamp(glm::ivec2(glm::clamp(c, glm::dvec2(-1.0), glm::dvec2(n_))), glm::ivec2(0),
                      glm::ivec2(n_ - 1));
  }
  std::size_t cellIndex(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(n_) + static_cast<std::size_t>(x);
  }

  int axis_, u_, v_;
  std::span<const glm::vec3> pos_;
  std::span<const std::uint32_t> idx_;
  int n_ = 1;
  glm::dvec2 lo_{0.0}, scale_{1.0};
  std::vector<std::uint32_t> offsets_;  // (n^2 + 1) into items_
  std::vector<std::uint32_t> items_;    // triangle ids per cell
};

bool holdsPoint(const Bounds& box, const glm::vec3& p) {
  return glm::all(glm::greaterThanEqual(p, box.min)) && glm::all(glm::lessThanEqual(p, box.max));
}

double boxVolume(const Bounds& box) {
  const glm::dvec3 e = glm::dvec3(box.max) - glm::dvec3(box.min);
  return e.x * e.y * e.z;
}

}  // namespace

Result<InnerLayers> findInnerLayers(std::span<const glm::vec3> pos,
                                    std::span<const std::uint32_t> idx,
                                    const InnerLayerOptions& opt) {
  const std::size_t nv = pos.size();
  if (!(opt.min_inside_fraction > 0.0f && opt.min_inside_fraction <= 1.0f)) {
    return fail("inner layers: min_inside_fraction {} not in (0, 1]", opt.min_inside_fraction);
  }
  if (idx.size() % 3 != 0) {
    return fail("inner layers: index count {} not a multiple of 3", idx.size());
  }
  for (std::size_t i = 0; i < idx.size(); ++i) {
    if (idx[i] >= nv) return fail("inner layers: index {} = {} beyond {} vertices", i, idx[i], nv);
  }
  for (std::size_t v = 0; v < nv; ++v) {
    if (!std::isfinite(pos[v].x) || !std::isfinite(pos[v].y) || !std::isfinite(pos[v].z)) {
      return fail("inner layers: vertex {} not finite", v);
    }
  }

  // Components: triangles join their vertices, equal positions are one vertex.
  DisjointSets uf(nv);
  for (std::size_t f = 0; f < idx.size(); f += 3) {
    uf.join(idx[f], idx[f + 1]);
    uf.join(idx[f], idx[f + 2]);
  }
  const std::vector<std::uint32_t> first = firstCopies(pos);
  for (std::size_t v = 0; v < nv; ++v) uf.join(static_cast<std::uint32_t>(v), first[v]);

  // Number the roots that hold a triangle; count vertices and triangles.
  InnerLayers out;
  std::vector<std::int32_t> root_id(nv, -1);
  std::vector<MeshComponent> found;
  std::vector<std::uint32_t> first_vertex;
  for (std::size_t f = 0; f < idx.size(); f += 3) {
    const std::uint32_t r = uf.find(idx[f]);
    if (root_id[r] < 0) {
      root_id[r] = static_cast<std::int32_t>(found.size());
      found.emplace_back();
      first_vertex.push_back(r);  // the root is the component's smallest vertex
    }
    ++found[static_cast<std::size_t>(root_id[r])].triangles;
  }
  // Largest first, then by first vertex.
  std::vector<std::int32_t> rank(found.size());
  {
    std::vector<std::uint32_t> vcount(found.size(), 0);
    for (std::size_t v = 0; v < nv; ++v) {
      const std::int32_t c = root_id[uf.find(static_cast<std::uint32_t>(v))];
      if (c >= 0) ++vcount[static_cast<std::size_t>(c)];
    }
    std::vector<std::int32_t> order(found.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
      const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
      if (vcount[ua] != vcount[ub]) return vcount[ua] > vcount[ub];
      return first_vertex[ua] < first_vertex[ub];
    });
    for (std::size_t i = 0; i < order.size(); ++i)
      rank[static_cast<std::size_t>(order[i])] = static_cast<std::int32_t>(i);
    out.components.resize(found.size());
    for (std::size_t c = 0; c < found.size(); ++c)
      out.components[static_cast<std::size_t>(rank[c])].triangles = found[c].triangles;
  }
  out.component.assign(nv, -1);
  std::vector<std::vector<std::uint32_t>> members(out.components.size());
  for (std::size_t v = 0; v < nv; ++v) {
    const std::int32_t c = root_id[uf.find(static_cast<std::uint32_t>(v))];
    if (c < 0) continue;
    const std::int32_t k = rank[static_cast<std::size_t>(c)];
    out.component[v] = k;
    MeshComponent& mc = out.components[static_cast<std::size_t>(k)];
    if (mc.vertices == 0) {
      mc.box = {pos[v], pos[v]};
    } else {
      mc.box.min = glm::min(mc.box.min, pos[v]);
      mc.box.max = glm::max(mc.box.max, pos[v]);
    }
    ++mc.vertices;
    members[static_cast<std::size_t>(k)].push_back(static_cast<std::uint32_t>(v));
  }
  out.inner.assign(nv, 0);
  if (out.components.empty()) return out;
  out.outer = 0;
  if (out.components.size() == 1) return out;

  // Each component's triangles, and its grids per axis when a smaller one is tested in it.
  std::vector<std::vector<std::uint32_t>> tris(out.components.size());
  for (std::size_t f = 0; f < idx.size(); f += 3) {
    tris[static_cast<std::size_t>(out.component[idx[f]])].push_back(
        static_cast<std::uint32_t>(f / 3));
  }
  std::vector<std::array<std::unique_ptr<AxisGrid>, 3>> grids(out.components.size());
  const auto grid = [&](std::size_t d, int axis) -> const AxisGrid& {
    auto& g = grids[d][static_cast<std::size_t>(axis)];
    if (!g) g = std::make_unique<AxisGrid>(axis, tris[d], pos, idx, out.components[d].box);
    return *g;
  };

  // A component is inner when enough of its vertices are inside a component around it.
  for (std::size_t c = 1; c < out.components.size(); ++c) {
    MeshComponent& mc = out.components[c];
    const glm::vec3 centre = 0.5f * (mc.box.min + mc.box.max);
    const auto n = static_cast<int>(members[c].size());
    const int needed = static_cast<int>(std::ceil(opt.min_inside_fraction * static_cast<float>(n)));
    for (std::size_t d = 0; d < out.components.size() && !mc.inner; ++d) {
      const MeshComponent& md = out.components[d];
      if (d == c || md.triangles < 4 || !holdsPoint(md.box, centre) ||
          !(boxVolume(md.box) > boxVolume(mc.box))) {
        continue;
      }
      int inside = 0;
      int outside = 0;
      for (const std::uint32_t v : members[c]) {
        int votes = 0;
        if (holdsPoint(md.box, pos[v])) {
          for (int axis = 0; axis < 3; ++axis) {
            const std::array<int, 2> k = grid(d, axis).crossings(pos[v]);
            votes += (k[0] & 1) + (k[1] & 1);
          }
        }
        if (votes >= kInsideVotes) {
          ++inside;
        } else if (++outside > n - needed) {
          break;  // too many outside already
        }
      }
      if (inside >= needed) {
        mc.inner = true;
        mc.container = static_cast<int>(d);
        mc.inside_share = static_cast<float>(inside) / static_cast<float>(n);
      }
    }
    if (!mc.inner) continue;
    for (const std::uint32_t v : members[c]) out.inner[v] = 1;
    out.inner_vertices += n;
  }
  return out;
}

Result<int> carryInnerLayersRigidly(std::span<const std::uint8_t> inner, Calibration& c) {
  const std::size_t nv = inner.size();
  if (c.vertex_class.size() != nv || c.prims.size() != nv) {
    return fail("inner layers: calibration has {} classes and {} primitive sets for {} vertices",
                c.vertex_class.size(), c.prims.size(), nv);
  }
  if (c.rigid.size() != nv) c.rigid.assign(nv, 0);
  int marked = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (inner[v] == 0) continue;
    c.vertex_class[v] = VertexClass::kFree;
    c.prims[v] = {kNoPrimitive, kNoPrimitive, kNoPrimitive, kNoPrimitive};
    c.rigid[v] = kRigidInner;
    if (c.w.size() == nv) c.w[v] = 1.0f;
    if (c.slope.size() == nv) c.slope[v] = kInnerSlope;
    ++marked;
  }
  // Their pairs dropped.
  if (marked > 0 && c.pair_offsets.size() == nv + 1 && c.pair_offsets[nv] == c.pairs.size()) {
    std::vector<VertexPair> kept;
    kept.reserve(c.pairs.size());
    std::uint32_t begin = 0;
    for (std::size_t v = 0; v < nv; ++v) {
      const std::uint32_t end = c.pair_offsets[v + 1];
      if (inner[v] == 0) kept.insert(kept.end(), c.pairs.begin() + begin, c.pairs.begin() + end);
      begin = end;
      c.pair_offsets[v + 1] = static_cast<std::uint32_t>(kept.size());
    }
    c.pairs = std::move(kept);
  }
  return marked;
}

}  // namespace vistel
