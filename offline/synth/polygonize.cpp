// Marching tetrahedra (Doi & Koide 1991) over a Kuhn/Freudenthal cube split, made adaptive
// by a restricted (2:1) octree whose transition cubes are coned from their centres, which
// keeps the tetrahedralisation conforming.
#include "offline/synth/polygonize.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <numeric>

#include "common/base/disjoint_sets.hpp"

namespace vistel::synth {
namespace {

using Point = glm::ivec3;  // integer lattice coordinates, in units of half the finest cube

std::uint64_t packKey(const Point& p) {
  return static_cast<std::uint64_t>(p.x) | (static_cast<std::uint64_t>(p.y) << 21) |
         (static_cast<std::uint64_t>(p.z) << 42);
}

std::uint64_t mixBits(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  x ^= x >> 31;
  return x;
}

// Open-addressing hash map from a pair of 64-bit keys to a 32-bit value (linear probing,
// grows at half load). Deterministic: its contents never depend on iteration order.
class PairMap {
 public:
  static constexpr std::uint64_t kEmpty = ~0ull;

  PairMap() { reset(1u << 16); }

  // The slot's value for (a, b); `inserted` tells whether it was just created (value 0).
  std::uint32_t& at(std::uint64_t a, std::uint64_t b, bool& inserted) {
    if (2 * (count_ + 1) > keys_a_.size()) grow();
    std::size_t i = mixBits(a ^ mixBits(b)) & mask_;
    while (keys_a_[i] != kEmpty) {
      if (keys_a_[i] == a && keys_b_[i] == b) {
        inserted = false;
        return values_[i];
      }
      i = (i + 1) & mask_;
    }
    keys_a_[i] = a;
    keys_b_[i] = b;
    values_[i] = 0;
    ++count_;
    inserted = true;
    return values_[i];
  }

 private:
  void reset(std::size_t capacity) {
    keys_a_.assign(capacity, kEmpty);
    keys_b_.assign(capacity, 0);
    values_.assign(capacity, 0);
    mask_ = capacity - 1;
    count_ = 0;
  }
  void grow() {
    std::vector<std::uint64_t> a = std::move(keys_a_);
    std::vector<std::uint64_t> b = std::move(keys_b_);
    std::vector<std::uint32_t> v = std::move(values_);
    reset(a.size() * 2);
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (a[i] == kEmpty) continue;
      bool inserted = false;
      at(a[i], b[i], inserted) = v[i];
    }
  }

  std::vector<std::uint64_t> keys_a_;
  std::vector<std::uint64_t> keys_b_;
  std::vector<std::uint32_t> values_;
  std::size_t mask_ = 0;
  std::size_t count_ = 0;
};

// Open-addressing hash map from a 64-bit key to a float (linear probing, grows at half load).
class ValueMap {
 public:
  static constexpr std::uint64_t kEmpty = ~0ull;

  ValueMap() { reset(1u << 16); }

  // The slot for key; `inserted` tells whether it was just created.
  float& at(std::uint64_t key, bool& inserted) {
    if (2 * (count_ + 1) > keys_.size()) grow();
    std::size_t i = mixBits(key) & mask_;
    while (keys_[i] != kEmpty) {
      if (keys_[i] == key) {
        inserted = false;
        return values_[i];
      }
      i = (i + 1) & mask_;
    }
    keys_[i] = key;
    values_[i] = 0.0f;
    ++count_;
    inserted = true;
    return values_[i];
  }

 private:
  void reset(std::size_t capacity) {
    keys_.assign(capacity, kEmpty);
    values_.assign(capacity, 0.0f);
    mask_ = capacity - 1;
    count_ = 0;
  }
  void grow() {
    std::vector<std::uint64_t> k = std::move(keys_);
    std::vector<float> v = std::move(values_);
    reset(k.size() * 2);
    for (std::size_t i = 0; i < k.size(); ++i) {
      if (k[i] == kEmpty) continue;
      bool inserted = false;
      at(k[i], inserted) = v[i];
    }
  }

  std::vector<std::uint64_t> keys_;
  std::vector<float> values_;
  std::size_t mask_ = 0;
  std::size_t count_ = 0;
};

class Polygonizer {
 public:
  Polygonizer(const ImplicitBody& body, const PolygonizeSettings& settings)
      : body_(body), levels_(0) {
    for (const FineRegion& r : settings.fine_regions)
      levels_ = std::max(levels_, std::clamp(r.halvings, 0, 3));
    coarse_side_ = 1 << (levels_ + 1);
    // Top-level blocks of at most ~7 cm, each evaluated with the primitives near it.
    block_ = 1;
    while (2 * block_ * settings.coarse_cell <= 0.07f * settings.shape_scale) block_ *= 2;
    unit_ = static_cast<double>(settings.coarse_cell) / coarse_side_;
    // Domain in coarse cubes, with one empty cube of margin, rounded up to whole blocks.
    const glm::dvec3 lo =
        glm::dvec3(settings.domain.min) - static_cast<double>(settings.coarse_cell);
    const glm::dvec3 hi =
        glm::dvec3(settings.domain.max) + static_cast<double>(settings.coarse_cell);
    origin_ = lo;
    for (int a = 0; a < 3; ++a) {
      const int n = static_cast<int>(std::ceil((hi[a] - lo[a]) / settings.coarse_cell));
      coarse_count_[a] = (n + block_ - 1) / block_ * block_;
      assert(coarse_count_[a] * coarse_side_ < (1 << 21));  // lattice keys pack 21 bits
    }
    // Refinement level of every coarse cube: the region's halvings inside a fine region, one
    // less per coarse cube of Chebyshev distance from it (a 2:1 graded octree).
    coarse_level_.assign(
        static_cast<std::size_t>(coarse_count_.x) * coarse_count_.y * coarse_count_.z, 0);
    for (const FineRegion& region : settings.fine_regions) {
      const Box& box = region.box;
      const int halvings = std::clamp(region.halvings, 0, 3);
      const glm::ivec3 b0 = glm::ivec3(
          glm::floor((glm::dvec3(box.min) - origin_) / static_cast<double>(settings.coarse_cell)));
      const glm::ivec3 b1 = glm::ivec3(glm::ceil((glm::dvec3(box.max) - origin_) /
                                                 static_cast<double>(settings.coarse_cell))) -
                            1;
      for (int z = std::max(b0.z - halvings, 0);
           z <= std::min(b1.z + halvings, coarse_count_.z - 1); ++z) {
        for (int y = std::max(b0.y - halvings, 0);
             y <= std::min(b1.y + halvings, coarse_count_.y - 1); ++y) {
          for (int x = std::max(b0.x - halvings, 0);
               x <= std::min(b1.x + halvings, coarse_count_.x - 1); ++x) {
            const glm::ivec3 c(x, y, z);
            const glm::ivec3 dist = glm::max(glm::max(b0 - c, c - b1), glm::ivec3(0));
            const int level = halvings - std::max({dist.x, dist.y, dist.z});
            std::uint8_t& slot = coarse_level_[coarseIndex(c)];
            slot = static_cast<std::uint8_t>(std::max<int>(slot, level));
          }
        }
      }
    }
    // Highest level among each coarse cube's 27 neighbours: cubes at that level need no
    // transition checks.
    neighbourhood_level_.assign(coarse_level_.size(), 0);
    for (int z = 0; z < coarse_count_.z; ++z) {
      for (int y = 0; y < coarse_count_.y; ++y) {
        for (int x = 0; x < coarse_count_.x; ++x) {
          int best = 0;
          for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
              for (int dx = -1; dx <= 1; ++dx) {
                const glm::ivec3 c(x + dx, y + dy, z + dz);
                if (glm::any(glm::lessThan(c, glm::ivec3(0))) ||
                    glm::any(glm::greaterThanEqual(c, coarse_count_))) {
                  continue;
                }
                best = std::max<int>(best, coarse_level_[coarseIndex(c)]);
              }
            }
          }
          neighbourhood_level_[coarseIndex(glm::ivec3(x, y, z))] = static_cast<std::uint8_t>(best);
        }
      }
    }
    // Samples this close to zero are nudged outward so that no vertex sits on the surface.
    epsilon_ = static_cast<float>(1e-3 * unit_);
  }

  TriangleMesh run() {
    const int block_side = block_ * coarse_side_;
    const float block_radius = static_cast<float>(0.5 * std::sqrt(3.0) * block_side * unit_);
    for (int z = 0; z < coarse_count_.z / block_; ++z) {
      for (int y = 0; y < coarse_count_.y / block_; ++y) {
        for (int x = 0; x < coarse_count_.x / block_; ++x) {
          const Point min = Point(x, y, z) * block_side;
          body_.select(glm::vec3(toModel(min + Point(block_side / 2))), block_radius, subset_);
          visit(min, block_side);
        }
      }
    }
    return keepLargestComponent();
  }

 private:
  std::size_t coarseIndex(const glm::ivec3& c) const {
    return (static_cast<std::size_t>(c.z) * coarse_count_.y + c.y) * coarse_count_.x + c.x;
  }

  // Refinement level of the leaf containing lattice point p (p strictly inside a cube).
  int leafLevel(const Point& p) const {
    const int shift = levels_ + 1;
    const glm::ivec3 c(p.x >> shift, p.y >> shift, p.z >> shift);
    if (glm::any(glm::lessThan(c, glm::ivec3(0))) ||
        glm::any(glm::greaterThanEqual(c, coarse_count_))) {
      return 0;
    }
    return coarse_level_[coarseIndex(c)];
  }

  glm::dvec3 toModel(const Point& p) const { return origin_ + unit_ * glm::dvec3(p); }

  // Field value at a lattice point (cached; never exactly zero).
  float sample(const Point& p) {
    bool inserted = false;
    float& slot = values_.at(packKey(p), inserted);
    if (!inserted) return slot;
    float v = body_.value(glm::vec3(toModel(p)), subset_);
    if (std::abs(v) < epsilon_) v = epsilon_;
    slot = v;
    return v;
  }

  // Descends the octree below the cube (min, side), skipping cubes the field proves empty.
  void visit(const Point& min, int side) {
    const Point center = min + Point(side / 2);
    const float f = sample(center);
    const double half_diagonal = 0.5 * std::sqrt(3.0) * side * unit_;
    if (std::abs(f) > half_diagonal * (1.0 + 1e-5) + 1e-7) return;
    if (side <= coarse_side_) {
      const int level = levels_ + 1 - std::countr_zero(static_cast<unsigned>(side));
      if (level == leafLevel(center)) {
        emitCube(min, side, level);
        return;
      }
    }
    const int h = side / 2;
    for (int i = 0; i < 8; ++i) visit(min + Point(i & 1, (i >> 1) & 1, (i >> 2) & 1) * h, h);
  }

  bool finer(const Point& cube_center, int level) const { return leafLevel(cube_center) > level; }

  // Splits one leaf cube into tetrahedra and contours them.
  void emitCube(const Point& min, int side, int level) {
    const Point center = min + Point(side / 2);
    const int h = side / 2;
    // Faces whose neighbour is finer, and edges that a finer cube touches (only possible when
    // a neighbouring coarse cube is refined further than this cube).
    std::array<bool, 6> face_refined{};
    bool transition = false;
    const int shift = levels_ + 1;
    const glm::ivec3 coarse(center.x >> shift, center.y >> shift, center.z >> shift);
    if (neighbourhood_level_[coarseIndex(coarse)] > level) {
      for (int f = 0; f < 6; ++f) {
        Point nb = center;
        nb[f / 2] += (f % 2 == 0 ? -side : side);
        face_refined[static_cast<std::size_t>(f)] = finer(nb, level);
        transition = transition || face_refined[static_cast<std::size_t>(f)];
      }
      for (int a = 0; a < 3 && !transition; ++a) {
        for (int e = 0; e < 4 && !transition; ++e) transition = edgeSplit(min, side, level, a, e);
      }
    }
    if (!transition) {
      // Kuhn split: six tetrahedra along the main diagonal (corner i = min + side * bits of i).
      std::array<Point, 8> corner;
      std::array<float, 8> value;
      int inside = 0;
      for (int i = 0; i < 8; ++i) {
        corner[static_cast<std::size_t>(i)] = min + Point(i & 1, (i >> 1) & 1, (i >> 2) & 1) * side;
        value[static_cast<std::size_t>(i)] = sample(corner[static_cast<std::size_t>(i)]);
        inside += value[static_cast<std::size_t>(i)] < 0.0f ? 1 : 0;
      }
      if (inside == 0 || inside == 8) return;
      static constexpr std::array<std::array<int, 3>, 6> kOrders{
          {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
      for (const auto& order : kOrders) {
        std::array<int, 4> ids{0, 0, 0, 0};
        for (std::size_t k = 0; k < 3; ++k) ids[k + 1] = ids[k] | (1 << order[k]);
        std::array<Point, 4> t;
        std::array<float, 4> v;
        for (std::size_t k = 0; k < 4; ++k) {
          t[k] = corner[static_cast<std::size_t>(ids[k])];
          v[k] = value[static_cast<std::size_t>(ids[k])];
        }
        contourTet(t, v);
      }
      return;
    }
    // Transition cube: cone every face triangle to the centre.
    for (int f = 0; f < 6; ++f) {
      const int a = f / 2;
      const int b = (a + 1) % 3;
      const int c = (a + 2) % 3;
      Point o = min;
      o[a] += (f % 2 == 0 ? 0 : side);
      Point eb(0), ec(0);
      eb[b] = 1;
      ec[c] = 1;
      if (face_refined[static_cast<std::size_t>(f)]) {
        for (int i = 0; i < 4; ++i) {
          const Point q = o + eb * (h * (i & 1)) + ec * (h * (i >> 1));
          contourTet({center, q, q + eb * h, q + eb * h + ec * h});
          contourTet({center, q, q + eb * h + ec * h, q + ec * h});
        }
        continue;
      }
      // The face's edges in cyclic order: (o,o+b), (o+b,o+b+c), (o+b+c,o+c), (o+c,o).
      const std::array<Point, 4> corner{o, o + eb * side, o + eb * side + ec * side, o + ec * side};
      std::array<bool, 4> split{};
      bool any_split = false;
      for (int e = 0; e < 4; ++e) {
        const Point p0 = corner[static_cast<std::size_t>(e)];
        const Point p1 = corner[static_cast<std::size_t>((e + 1) % 4)];
        split[static_cast<std::size_t>(e)] =
            edgeSplitAt((p0 + p1) / 2, p0 != p1 ? axisOf(p1 - p0) : 0, side, level);
        any_split = any_split || split[static_cast<std::size_t>(e)];
      }
      if (!any_split) {
        contourTet({center, corner[0], corner[1], corner[2]});
        contourTet({center, corner[0], corner[2], corner[3]});
        continue;
      }
      // Fan from the face centre over the edges, halved where split.
      const Point face_center = o + eb * h + ec * h;
      for (int e = 0; e < 4; ++e) {
        const Point p0 = corner[static_cast<std::size_t>(e)];
        const Point p1 = corner[static_cast<std::size_t>((e + 1) % 4)];
        if (split[static_cast<std::size_t>(e)]) {
          const Point mid = (p0 + p1) / 2;
          contourTet({center, face_center, p0, mid});
          contourTet({center, face_center, mid, p1});
        } else {
          contourTet({center, face_center, p0, p1});
        }
      }
    }
  }

  static int axisOf(const Point& d) { return d.x != 0 ? 0 : (d.y != 0 ? 1 : 2); }

  // Edge e (0..3) along axis a of the cube (min, side).
  bool edgeSplit(const Point& min, int side, int level, int a, int e) const {
    Point mid = min;
    mid[a] += side / 2;
    mid[(a + 1) % 3] += (e & 1) * side;
    mid[(a + 2) % 3] += (e >> 1) * side;
    return edgeSplitAt(mid, a, side, level);
  }

  // Whether a finer cube touches the cube edge with midpoint `mid` along axis a.
  bool edgeSplitAt(const Point& mid, int a, int side, int level) const {
    const int b = (a + 1) % 3;
    const int c = (a + 2) % 3;
    for (int i = 0; i < 4; ++i) {
      Point q = mid;
      q[b] += (i & 1) ? side / 2 : -side / 2;
      q[c] += (i & 2) ? side / 2 : -side / 2;
      if (finer(q, level)) return true;
    }
    return false;
  }

  // Marching tetrahedra on one tetrahedron (any vertex order).
  void contourTet(const std::array<Point, 4>& t) {
    std::array<float, 4> v;
    for (std::size_t i = 0; i < 4; ++i) v[i] = sample(t[i]);
    contourTet(t, v);
  }
  void contourTet(std::array<Point, 4> t, std::array<float, 4> v) {
    // Positive orientation, from exact integer arithmetic.
    const glm::i64vec3 e1(t[1] - t[0]), e2(t[2] - t[0]), e3(t[3] - t[0]);
    const std::int64_t det = e1.x * (e2.y * e3.z - e2.z * e3.y) -
                             e1.y * (e2.x * e3.z - e2.z * e3.x) +
                             e1.z * (e2.x * e3.y - e2.y * e3.x);
    assert(det != 0);
    if (det < 0) {
      std::swap(t[2], t[3]);
      std::swap(v[2], v[3]);
    }
    int inside_mask = 0;
    for (int i = 0; i < 4; ++i) {
      if (v[static_cast<std::size_t>(i)] < 0.0f) inside_mask |= 1 << i;
    }
    const int inside = std::popcount(static_cast<unsigned>(inside_mask));
    if (inside == 0 || inside == 4) return;
    const auto vertex = [&](int i, int j) {
      return edgeVertex(t[static_cast<std::size_t>(i)], v[static_cast<std::size_t>(i)],
                        t[static_cast<std::size_t>(j)], v[static_cast<std::size_t>(j)]);
    };
    if (inside == 1 || inside == 3) {
      // The lone vertex first, in an even permutation (keeps the orientation).
      static constexpr std::array<std::array<int, 4>, 4> kLone{
          {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 0, 1, 3}, {3, 0, 2, 1}}};
      const int lone_mask = inside == 1 ? inside_mask : (~inside_mask & 15);
      const auto& p =
          kLone[static_cast<std::size_t>(std::countr_zero(static_cast<unsigned>(lone_mask)))];
      const std::uint32_t a = vertex(p[0], p[1]);
      const std::uint32_t b = vertex(p[0], p[2]);
      const std::uint32_t c = vertex(p[0], p[3]);
      // Normals point from the inside to the outside.
      if (inside == 1) {
        addTriangle(a, b, c);
      } else {
        addTriangle(a, c, b);
      }
      return;
    }
    // Two inside: the inside pair first, in an even permutation.
    static constexpr std::array<std::array<int, 4>, 16> kPair{{
        {},
        {},
        {},
        {0, 1, 2, 3},  // mask 3 = {0,1}
        {},
        {0, 2, 3, 1},  // 5 = {0,2}
        {1, 2, 0, 3},  // 6 = {1,2}
        {},
        {},
        {0, 3, 1, 2},  // 9 = {0,3}
        {1, 3, 2, 0},  // 10 = {1,3}
        {},
        {2, 3, 0, 1},  // 12 = {2,3}
        {},
        {},
        {},
    }};
    const auto& p = kPair[static_cast<std::size_t>(inside_mask)];
    const std::uint32_t ac = vertex(p[0], p[2]);
    const std::uint32_t ad = vertex(p[0], p[3]);
    const std::uint32_t bd = vertex(p[1], p[3]);
    const std::uint32_t bc = vertex(p[1], p[2]);
    // Split the quad (ac, ad, bd, bc) along its shorter diagonal.
    const float d1 = glm::distance(positions_[ac], positions_[bd]);
    const float d2 = glm::distance(positions_[ad], positions_[bc]);
    if (d1 <= d2) {
      addTriangle(ac, ad, bd);
      addTriangle(ac, bd, bc);
    } else {
      addTriangle(ac, ad, bc);
      addTriangle(ad, bd, bc);
    }
  }

  // The surface vertex on lattice edge (a, b), shared by every tetrahedron using the edge.
  std::uint32_t edgeVertex(const Point& a, float va, const Point& b, float vb) {
    std::uint64_t ka = packKey(a), kb = packKey(b);
    bool swapped = false;
    if (ka > kb) {
      std::swap(ka, kb);
      swapped = true;
    }
    bool inserted = false;
    std::uint32_t& slot = edges_.at(ka, kb, inserted);
    if (!inserted) return slot;
    // Interpolate from the lower key so the position does not depend on the caller.
    const Point& p0 = swapped ? b : a;
    const Point& p1 = swapped ? a : b;
    const double v0 = swapped ? vb : va;
    const double v1 = swapped ? va : vb;
    const double t = v0 / (v0 - v1);
    const glm::dvec3 x0 = toModel(p0), x1 = toModel(p1);
    slot = static_cast<std::uint32_t>(positions_.size());
    positions_.emplace_back(x0 + t * (x1 - x0));
    return slot;
  }

  void addTriangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    indices_.insert(indices_.end(), {a, b, c});
  }

  // Keeps the connected component with the most triangles.
  TriangleMesh keepLargestComponent() {
    DisjointSets pieces(positions_.size());
    const auto find = [&pieces](std::uint32_t x) { return pieces.find(x); };
    for (std::size_t t = 0; t < indices_.size(); t += 3) {
      for (std::size_t k = 1; k < 3; ++k) pieces.join(indices_[t], indices_[t + k]);
    }
    std::vector<std::uint32_t> triangles_per_root(positions_.size(), 0);
    for (std::size_t t = 0; t < indices_.size(); t += 3) ++triangles_per_root[find(indices_[t])];
    const auto best = static_cast<std::uint32_t>(
        std::max_element(triangles_per_root.begin(), triangles_per_root.end()) -
        triangles_per_root.begin());
    TriangleMesh out;
    std::vector<std::uint32_t> remap(positions_.size(), ~0u);
    for (std::size_t v = 0; v < positions_.size(); ++v) {
      if (find(static_cast<std::uint32_t>(v)) != best) continue;
      remap[v] = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(positions_[v]);
    }
    for (std::size_t t = 0; t < indices_.size(); t += 3) {
      if (find(indices_[t]) != best) continue;
      for (int k = 0; k < 3; ++k)
        out.indices.push_back(remap[indices_[t + static_cast<std::size_t>(k)]]);
    }
    return out;
  }

  const ImplicitBody& body_;
  int levels_;
  int coarse_side_;     // lattice units per coarse cube edge
  int block_;           // coarse cubes per top-level block edge (a power of two)
  ShapeSubset subset_;  // primitives near the current top-level block
  double unit_;         // metres per lattice unit
  glm::dvec3 origin_;
  glm::ivec3 coarse_count_{0};
  std::vector<std::uint8_t> coarse_level_;         // per coarse cube
  std::vector<std::uint8_t> neighbourhood_level_;  // max over its 27 neighbours
  float epsilon_;
  ValueMap values_;  // sample key -> field value
  PairMap edges_;    // lattice edge -> vertex index
  std::vector<glm::vec3> positions_;
  std::vector<std::uint32_t> indices_;
};

}  // namespace

TriangleMesh polygonize(const ImplicitBody& body, const PolygonizeSettings& settings) {
  return Polygonizer(body, settings).run();
}

}  // namespace vistel::synth
