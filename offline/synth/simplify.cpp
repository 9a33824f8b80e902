// Edge collapses in order of length relative to the desired length (a bucket queue), the
// merged vertex placed by Garland & Heckbert 1997, "Surface simplification using quadric
// error metrics": each vertex carries the sum of its faces' plane quadrics (weighted by
// area). Stale queue entries are recognised by per-vertex stamps and skipped; refused ones
// are queued again a few times, since a neighbour's collapse may unblock them.
#include "offline/synth/simplify.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace vistel::synth {
namespace {

constexpr std::uint32_t kDead = ~0u;
constexpr int kMaxRetries = 3;

// Symmetric 4x4 quadric [A b; b^T c] stored as its upper triangle.
struct Quadric {
  std::array<double, 10> q{};  // xx xy xz xw yy yz yw zz zw ww

  void addPlane(const glm::dvec3& n, double d, double weight) {
    const std::array<double, 4> p{n.x, n.y, n.z, d};
    int k = 0;
    for (int i = 0; i < 4; ++i) {
      for (int j = i; j < 4; ++j)
        q[static_cast<std::size_t>(k++)] +=
            weight * p[static_cast<std::size_t>(i)] * p[static_cast<std::size_t>(j)];
    }
  }
  Quadric& operator+=(const Quadric& o) {
    for (std::size_t i = 0; i < q.size(); ++i) q[i] += o.q[i];
    return *this;
  }
  double error(const glm::dvec3& p) const {
    const double x = p.x, y = p.y, z = p.z;
    return q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x + q[4] * y * y +
           2 * q[5] * y * z + 2 * q[6] * y + q[7] * z * z + 2 * q[8] * z + q[9];
  }
  // Minimiser of the error, if A is well conditioned.
  bool optimum(glm::dvec3& out) const {
    const glm::dmat3 a(q[0], q[1], q[2], q[1], q[4], q[5], q[2], q[5], q[7]);
    const double det = glm::determinant(a);
    const double scale = q[0] * q[4] * q[7];
    if (!(std::abs(det) > 1e-6 * std::abs(scale)) || std::abs(det) < 1e-300) return false;
    out = -(glm::inverse(a) * glm::dvec3(q[3], q[6], q[8]));
    return true;
  }
};

struct Candidate {
  double cost;
  std::uint32_t u, v;
  std::uint32_t stamp_u, stamp_v;
  int retries;  // times it was refused and queued again
};

// Priority queue over costs in [0, kMaxCost): candidates are binned by cost and popped
// first-in first-out within a bin. O(1) per operation; the order is deterministic.
class BucketQueue {
 public:
  static constexpr int kBuckets = 2048;
  static constexpr double kMaxCost = 4.0;

  void push(const Candidate& c) {
    const int b = std::clamp(static_cast<int>(c.cost * (kBuckets / kMaxCost)), 0, kBuckets - 1);
    buckets_[static_cast<std::size_t>(b)].items.push_back(c);
    lowest_ = std::min(lowest_, b);
    ++size_;
  }
  bool empty() const { return size_ == 0; }
  Candidate pop() {
    while (buckets_[static_cast<std::size_t>(lowest_)].empty()) ++lowest_;
    Bucket& bucket = buckets_[static_cast<std::size_t>(lowest_)];
    const Candidate c = bucket.items[bucket.head++];
    if (bucket.head == bucket.items.size()) {
      bucket.items.clear();
      bucket.head = 0;
    }
    --size_;
    return c;
  }

 private:
  struct Bucket {
    std::vector<Candidate> items;
    std::size_t head = 0;
    bool empty() const { return head == items.size(); }
  };
  std::array<Bucket, kBuckets> buckets_;
  int lowest_ = kBuckets - 1;
  std::size_t size_ = 0;
};

// 4 sqrt(3) area / sum of squared edge lengths: 1 for equilateral, 0 for degenerate.
double triangleQuality(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const double area2 = glm::length(glm::cross(b - a, c - a));  // twice the area
  const double l2 = glm::dot(b - a, b - a) + glm::dot(c - b, c - b) + glm::dot(a - c, a - c);
  return l2 > 0.0 ? 2.0 * std::sqrt(3.0) * area2 / l2 : 0.0;
}

class Simplifier {
 public:
  Simplifier(TriangleMesh& mesh, SimplifySettings& settings)
      : mesh_(mesh), lengths_(settings.edge_length), max_relative_(settings.max_relative_length) {
    const std::size_t nv = mesh.positions.size();
    const std::size_t nt = mesh.indices.size() / 3;
    pos_.resize(nv);
    for (std::size_t i = 0; i < nv; ++i) pos_[i] = glm::dvec3(mesh.positions[i]);
    tris_.resize(nt);
    vertex_tris_.resize(nv);
    quadrics_.resize(nv);
    stamp_.assign(nv, 0);
    for (std::size_t t = 0; t < nt; ++t) {
      for (std::size_t k = 0; k < 3; ++k) tris_[t][k] = mesh.indices[3 * t + k];
      for (std::size_t k = 0; k < 3; ++k)
        vertex_tris_[tris_[t][k]].push_back(static_cast<std::uint32_t>(t));
      // Area-weighted plane quadric of the triangle on each of its vertices.
      const glm::dvec3& a = pos_[tris_[t][0]];
      const glm::dvec3 n2 = glm::cross(pos_[tris_[t][1]] - a, pos_[tris_[t][2]] - a);
      const double len = glm::length(n2);
      if (len <= 0.0) continue;
      const glm::dvec3 n = n2 / len;
      Quadric q;
      q.addPlane(n, -glm::dot(n, a), 0.5 * len);
      for (std::size_t k = 0; k < 3; ++k) quadrics_[tris_[t][k]] += q;
    }
    alive_vertices_ = static_cast<int>(nv);
    normal_sum_.assign(nv, glm::dvec3(0.0));
    mark_.assign(nv, 0);
  }

  SimplifyStats run(int target_vertices) {
    for (std::size_t t = 0; t < tris_.size(); ++t) {
      // Average normal around each vertex (for the orientation check of slivers).
      const glm::dvec3& a = pos_[tris_[t][0]];
      const glm::dvec3 n = glm::cross(pos_[tris_[t][1]] - a, pos_[tris_[t][2]] - a);
      for (const std::uint32_t w : tris_[t]) normal_sum_[w] += n;
    }
    // One candidate per edge (the half-edge whose source has the smaller id).
    for (const auto& t : tris_) {
      for (std::size_t k = 0; k < 3; ++k) {
        const std::uint32_t a = t[k], b = t[(k + 1) % 3];
        if (a < b) push(a, b);
      }
    }
    while (alive_vertices_ > target_vertices && !queue_.empty()) {
      const Candidate c = queue_.pop();
      if (stamp_[c.u] != c.stamp_u || stamp_[c.v] != c.stamp_v) continue;
      if (tryCollapse(c.u, c.v)) {
        ++stats_.collapses;
        --alive_vertices_;
      } else {
        ++stats_.rejected;
        // Try again later: the neighbourhood may have changed by then.
        if (c.retries < kMaxRetries) {
          Candidate again = c;
          again.cost = c.cost * 1.5 + 1e-30;
          ++again.retries;
          queue_.push(again);
        }
      }
    }
    compact();
    return stats_;
  }

 private:
  // Positions for merging u and v, best quadric error first: the optimum (when well
  // conditioned and near the edge), the midpoint, the two ends. Returns how many.
  int plan(std::uint32_t u, std::uint32_t v, std::array<glm::dvec3, 4>& out) const {
    Quadric q = quadrics_[u];
    q += quadrics_[v];
    const glm::dvec3 a = pos_[u], b = pos_[v];
    std::array<std::pair<double, glm::dvec3>, 4> options;
    int count = 0;
    glm::dvec3 opt;
    if (q.optimum(opt) && glm::distance(opt, 0.5 * (a + b)) < glm::distance(a, b)) {
      options[static_cast<std::size_t>(count++)] = {q.error(opt), opt};
    }
    for (const glm::dvec3& p : {0.5 * (a + b), a, b}) {
      options[static_cast<std::size_t>(count++)] = {q.error(p), p};
    }
    // Stable: equal errors keep the order above.
    std::stable_sort(options.begin(), options.begin() + count,
                     [](const auto& x, const auto& y) { return x.first < y.first; });
    for (int i = 0; i < count; ++i)
      out[static_cast<std::size_t>(i)] = options[static_cast<std::size_t>(i)].second;
    return count;
  }

  // Squared length over the desired lengths at both ends.
  double relativeLength2(const glm::dvec3& a, const glm::dvec3& b, std::uint32_t u,
                         std::uint32_t v) const {
    return glm::dot(a - b, a - b) / (static_cast<double>(lengths_[u]) * lengths_[v]);
  }

  void push(std::uint32_t u, std::uint32_t v) {
    queue_.push({relativeLength2(pos_[u], pos_[v], u, v), u, v, stamp_[u], stamp_[v], 0});
  }

  // The one-ring of x: on a closed manifold, the vertex after x in each of its triangles
  // names every neighbour exactly once.
  void neighbours(std::uint32_t x, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (const std::uint32_t t : vertex_tris_[x]) {
      const auto& tri = tris_[t];
      out.push_back(tri[0] == x ? tri[1] : (tri[1] == x ? tri[2] : tri[0]));
    }
  }

  // Whether merging u and v at `target` keeps edge lengths and triangle orientations sane.
  bool collapseAllowed(std::uint32_t u, std::uint32_t v, const glm::dvec3& target,
                       float merged_length) {
    // No edge from the merged vertex may grow far beyond its desired length.
    const double limit2 = static_cast<double>(max_relative_) * max_relative_;
    for (const auto* ring : {&nu_, &nv_}) {
      for (const std::uint32_t w : *ring) {
        if (w == u || w == v) continue;
        const double l2 = glm::dot(target - pos_[w], target - pos_[w]) /
                          (static_cast<double>(merged_length) * lengths_[w]);
        if (l2 > limit2) return false;
      }
    }
    const glm::dvec3 around = normal_sum_[u] + normal_sum_[v];
    // Surviving triangles must keep their orientation and a reasonable shape.
    for (const std::uint32_t x : {u, v}) {
      const std::uint32_t other = x == u ? v : u;
      for (const std::uint32_t t : vertex_tris_[x]) {
        const auto& tri = tris_[t];
        if (tri[0] == other || tri[1] == other || tri[2] == other) continue;
        std::array<glm::dvec3, 3> before, after;
        for (std::size_t k = 0; k < 3; ++k) {
          before[k] = pos_[tri[k]];
          after[k] = tri[k] == x ? target : before[k];
        }
        const glm::dvec3 n0 = glm::cross(before[1] - before[0], before[2] - before[0]);
        const glm::dvec3 n1 = glm::cross(after[1] - after[0], after[2] - after[0]);
        const double l1 = glm::length(n1);
        if (l1 <= 0.0) return false;
        const double q0 = triangleQuality(before[0], before[1], before[2]);
        const double q1 = triangleQuality(after[0], after[1], after[2]);
        // A sliver's normal means little: compare with the normal around the edge instead.
        const glm::dvec3 reference = q0 > 0.05 ? n0 : around;
        if (glm::dot(reference, n1) < 0.35 * glm::length(reference) * l1) return false;
        if (q1 < 0.02 && q1 < q0) return false;
      }
    }

    return true;
  }

  bool tryCollapse(std::uint32_t u, std::uint32_t v) {
    // The edge must still exist, with exactly two triangles.
    int shared = 0;
    for (const std::uint32_t t : vertex_tris_[u]) {
      const auto& tri = tris_[t];
      if (tri[0] == v || tri[1] == v || tri[2] == v) ++shared;
    }
    if (shared != 2) return false;
    // Link condition: u and v share exactly the two opposite vertices.
    neighbours(u, nu_);
    neighbours(v, nv_);
    ++epoch_;
    for (const std::uint32_t w : nu_) mark_[w] = epoch_;
    int common = 0;
    for (const std::uint32_t w : nv_) common += mark_[w] == epoch_ ? 1 : 0;
    if (common != 2) return false;
    if (nu_.size() + nv_.size() - 2 < 5) return false;  // would leave a tetrahedron or less

    std::array<glm::dvec3, 4> targets;
    const int count = plan(u, v, targets);
    const float merged_length = 0.5f * (lengths_[u] + lengths_[v]);
    int chosen = -1;
    for (int i = 0; i < count && chosen < 0; ++i) {
      if (collapseAllowed(u, v, targets[static_cast<std::size_t>(i)], merged_length)) chosen = i;
    }
    if (chosen < 0) return false;
    const glm::dvec3 target = targets[static_cast<std::size_t>(chosen)];

    // Collapse v into u.
    pos_[u] = target;
    quadrics_[u] += quadrics_[v];
    normal_sum_[u] += normal_sum_[v];
    lengths_[u] = merged_length;
    for (const std::uint32_t t : vertex_tris_[v]) {
      auto& tri = tris_[t];
      if (tri[0] == u || tri[1] == u || tri[2] == u) {
        // One of the two triangles on the edge: remove it from its third vertex too.
        for (const std::uint32_t w : tri) {
          if (w == u || w == v) continue;
          auto& list = vertex_tris_[w];
          list.erase(std::find(list.begin(), list.end(), t));
        }
        auto& list_u = vertex_tris_[u];
        list_u.erase(std::find(list_u.begin(), list_u.end(), t));
        tri = {kDead, kDead, kDead};
      } else {
        for (std::uint32_t& w : tri) {
          if (w == v) w = u;
        }
        vertex_tris_[u].push_back(t);
      }
    }
    vertex_tris_[v].clear();
    stamp_[v] = kDead;
    ++stamp_[u];
    // New candidates around the merged vertex.
    neighbours(u, nu_);
    for (const std::uint32_t w : nu_) {
      if (u < w) {
        push(u, w);
      } else {
        push(w, u);
      }
    }
    return true;
  }

  void compact() {
    std::vector<std::uint32_t> remap(pos_.size(), kDead);
    mesh_.positions.clear();
    std::vector<float> lengths;
    for (std::size_t i = 0; i < pos_.size(); ++i) {
      if (stamp_[i] == kDead) continue;
      remap[i] = static_cast<std::uint32_t>(mesh_.positions.size());
      mesh_.positions.emplace_back(pos_[i]);
      lengths.push_back(lengths_[i]);
    }
    lengths_ = std::move(lengths);
    mesh_.indices.clear();
    for (const auto& tri : tris_) {
      if (tri[0] == kDead) continue;
      for (const std::uint32_t w : tri) mesh_.indices.push_back(remap[w]);
    }
  }

  TriangleMesh& mesh_;
  std::vector<float>& lengths_;  // desired edge length per vertex
  float max_relative_;
  std::vector<glm::dvec3> pos_;
  std::vector<glm::dvec3> normal_sum_;  // sum of incident face normals (twice the area)
  std::vector<std::array<std::uint32_t, 3>> tris_;
  std::vector<std::vector<std::uint32_t>> vertex_tris_;
  std::vector<Quadric> quadrics_;
  std::vector<std::uint32_t> stamp_;  // bumped when a vertex moves; kDead once removed
  BucketQueue queue_;
  std::vector<std::uint32_t> nu_, nv_;  // scratch: one-rings
  std::vector<std::uint32_t> mark_;     // per vertex: epoch_ when last marked
  std::uint32_t epoch_ = 0;
  int alive_vertices_ = 0;
  SimplifyStats stats_;
};

}  // namespace

SimplifyStats simplify(TriangleMesh& mesh, SimplifySettings& settings) {
  return Simplifier(mesh, settings).run(settings.target_vertices);
}

}  // namespace vistel::synth
