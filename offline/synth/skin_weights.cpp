// Bone heat: Baran & Popovic 2007, "Automatic rigging and animation of 3D characters",
// with the cotangent Laplacian of Pinkall & Polthier 1993 / Meyer et al. 2003. Each vertex
// is attached to the bone of the primitive it came from instead of the nearest visible bone.
#include "offline/synth/skin_weights.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

namespace vistel::synth {
namespace {

// Heat constant c in H = c / d^2 (Baran & Popovic use 1): larger keeps weights closer to
// their bone; 2 blends a 4 cm-radius elbow over about +-5 cm.
constexpr double kHeat = 2.0;
// Weights below this share of a vertex's total are dropped (by subtraction, so continuously).
constexpr float kFaint = 0.02f;
// Rounds of weight smoothing over the mesh after the heat solve.
constexpr int kSmoothRounds = 3;
// Joints a vertex may depend on: own, parent, grandparent, nearest child and grandchild.
constexpr std::size_t kSlots = 5;
// Width in rings of the parent's band where siblings meet.
constexpr int kBandRings = 2;

float distanceToSegment(const glm::vec3& p, const BoneSegment& bone) {
  const glm::vec3 d = bone.tail - bone.head;
  const float len2 = glm::dot(d, d);
  const float t = len2 > 0.0f ? std::clamp(glm::dot(p - bone.head, d) / len2, 0.0f, 1.0f) : 0.0f;
  return glm::distance(p, bone.head + t * d);
}

// Cotangent of the angle at `apex` in the triangle (apex, a, b).
double cotangent(const glm::dvec3& apex, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 u = a - apex, v = b - apex;
  const double s = glm::length(glm::cross(u, v));
  return s > 0.0 ? glm::dot(u, v) / s : 0.0;
}

// One step from joint a towards joint b along the tree (a != b): down to the child on the
// way if a is an ancestor of b, otherwise up to a's parent.
int stepTowards(int a, int b, std::span<const int> parents) {
  for (int c = b; c >= 0; c = parents[static_cast<std::size_t>(c)]) {
    if (parents[static_cast<std::size_t>(c)] == a) return c;
  }
  return parents[static_cast<std::size_t>(a)];
}

bool treeNeighbours(int a, int b, std::span<const int> parents) {
  return a == b || parents[static_cast<std::size_t>(a)] == b ||
         parents[static_cast<std::size_t>(b)] == a;
}

}  // namespace

Result<SkinWeights> computeSkinWeights(const TriangleMesh& mesh, std::span<const int> labels_in,
                                       std::span<const int> parents,
                                       std::span<const BoneSegment> bones) {
  const std::size_t n = mesh.positions.size();
  const std::size_t joint_count = parents.size();
  std::vector<std::vector<std::uint32_t>> ring(n);
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    for (std::size_t k = 0; k < 3; ++k)
      ring[mesh.indices[t + k]].push_back(mesh.indices[t + (k + 1) % 3]);
  }

  // Labels of neighbouring vertices must be the same joint or parent and child (else no
  // joint could blend between them): where they are further apart in the tree (an upper
  // chest vertex next to an upper arm one), the vertex steps towards its neighbour's label
  // (to the clavicle). Sweeps in index order until nothing changes.
  std::vector<int> labels(labels_in.begin(), labels_in.end());
  for (int sweep = 0; sweep < 16; ++sweep) {
    bool changed = false;
    for (std::size_t i = 0; i < n; ++i) {
      for (const std::uint32_t nb : ring[i]) {
        if (treeNeighbours(labels[i], labels[nb], parents)) continue;
        labels[i] = stepTowards(labels[i], labels[nb], parents);
        changed = true;
      }
    }
    if (!changed) break;
  }

  // Cotangent Laplacian (positive semi-definite form) and barycentric vertex areas.
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(mesh.indices.size() * 4 + n);
  std::vector<double> area(n, 0.0);
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const std::array<std::uint32_t, 3> v{mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]};
    std::array<glm::dvec3, 3> p;
    for (std::size_t k = 0; k < 3; ++k) p[k] = glm::dvec3(mesh.positions[v[k]]);
    const double a = 0.5 * glm::length(glm::cross(p[1] - p[0], p[2] - p[0]));
    for (std::size_t k = 0; k < 3; ++k) {
      area[v[k]] += a / 3.0;
      // The edge opposite corner k, weighted by half the cotangent at k.
      const std::size_t i = (k + 1) % 3, j = (k + 2) % 3;
      const double w = 0.5 * std::max(cotangent(p[k], p[i], p[j]), 0.0);
      entries.emplace_back(v[i], v[j], -w);
      entries.emplace_back(v[j], v[i], -w);
      entries.emplace_back(v[i], v[i], w);
      entries.emplace_back(v[j], v[j], w);
    }
  }
  // Heat: area / d^2 at each vertex, d its distance to its own bone.
  std::vector<double> heat(n);
  for (std::size_t i = 0; i < n; ++i) {
    const float d = std::max(
        distanceToSegment(mesh.positions[i], bones[static_cast<std::size_t>(labels[i])]), 1e-3f);
    heat[i] = kHeat * area[i] / (static_cast<double>(d) * d);
    entries.emplace_back(i, i, heat[i]);
  }
  Eigen::SparseMatrix<double> system(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  system.setFromTriplets(entries.begin(), entries.end());

  // The joints a vertex may depend on: its own, that joint's parent and grandparent, and
  // down the tree only the child whose bone is nearest and that child's nearest child (so
  // siblings such as fingers or the two thighs split their parent's region between them
  // instead of overlapping).
  std::vector<std::vector<int>> children(joint_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    if (parents[j] >= 0)
      children[static_cast<std::size_t>(parents[j])].push_back(static_cast<int>(j));
  }
  const auto nearestChild = [&](int j, const glm::vec3& p) {
    int nearest = -1;
    float best = std::numeric_limits<float>::max();
    for (const int c : children[static_cast<std::size_t>(j)]) {
      const float d = distanceToSegment(p, bones[static_cast<std::size_t>(c)]);
      if (d < best) {
        best = d;
        nearest = c;
      }
    }
    return nearest;
  };
  // Where two siblings' shares meet (the crotch between the thighs, the webs between
  // fingers), give the parent a band a few rings wide, so that each sibling's weight can
  // fade to zero before the border instead of across one edge.
  {
    // The branch (child of the parent) each vertex falls in, for vertices labelled with a
    // parent joint or one of its children.
    const auto branch = [&](std::size_t i, int parent) {
      const int l = labels[i];
      if (l == parent) return nearestChild(parent, mesh.positions[i]);
      return parents[static_cast<std::size_t>(l)] == parent ? l : -1;
    };
    std::vector<int> distance(n, -1);
    std::vector<int> band_parent(n, -1);
    std::vector<std::uint32_t> frontier, next_frontier;
    for (std::size_t i = 0; i < n; ++i) {
      const int l = labels[i];
      const int p = parents[static_cast<std::size_t>(l)];
      for (const int candidate : {l, p}) {
        if (candidate < 0 || children[static_cast<std::size_t>(candidate)].size() < 2) continue;
        const int mine = branch(i, candidate);
        if (mine < 0) continue;
        for (const std::uint32_t nb : ring[i]) {
          const int theirs = branch(nb, candidate);
          if (theirs >= 0 && theirs != mine && distance[i] < 0) {
            distance[i] = 0;
            band_parent[i] = candidate;
            frontier.push_back(static_cast<std::uint32_t>(i));
          }
        }
      }
    }
    for (int step = 1; step <= kBandRings; ++step) {
      next_frontier.clear();
      for (const std::uint32_t i : frontier) {
        for (const std::uint32_t nb : ring[i]) {
          if (distance[nb] >= 0) continue;
          distance[nb] = step;
          band_parent[nb] = band_parent[i];
          next_frontier.push_back(nb);
        }
      }
      frontier.swap(next_frontier);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const int p = band_parent[i];
      if (p >= 0 && parents[static_cast<std::size_t>(labels[i])] == p) labels[i] = p;
    }
  }

  std::vector<std::array<int, kSlots>> allowed(n);  // -1 where unused
  for (std::size_t i = 0; i < n; ++i) {
    const int own = labels[i];
    const int parent = parents[static_cast<std::size_t>(own)];
    const int grandparent = parent >= 0 ? parents[static_cast<std::size_t>(parent)] : -1;
    const int child = nearestChild(own, mesh.positions[i]);
    const int grandchild = child >= 0 ? nearestChild(child, mesh.positions[i]) : -1;
    allowed[i] = {own, parent, grandparent, child, grandchild};
  }

  // Joint j's heat spreads only over the vertices that may depend on it and is held at 0
  // beyond them, so it fades out continuously at that region's border.
  std::vector<float> weight(n * kSlots, 0.0f);  // per vertex, per allowed slot
  std::vector<int> local(n, -1);
  std::vector<std::uint32_t> region;
  std::vector<std::uint8_t> slot_of;
  for (std::size_t j = 0; j < joint_count; ++j) {
    region.clear();
    slot_of.clear();
    bool owns = false;
    for (std::size_t i = 0; i < n; ++i) {
      owns = owns || static_cast<std::size_t>(labels[i]) == j;
      for (std::uint8_t k = 0; k < kSlots; ++k) {
        if (allowed[i][k] != static_cast<int>(j)) continue;
        local[i] = static_cast<int>(region.size());
        region.push_back(static_cast<std::uint32_t>(i));
        slot_of.push_back(k);
      }
    }
    if (!owns) {
      for (const std::uint32_t i : region) local[i] = -1;
      continue;
    }
    std::vector<Eigen::Triplet<double>> sub;
    for (const std::uint32_t i : region) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(system, i); it; ++it) {
        const int r = local[static_cast<std::size_t>(it.row())];
        if (r >= 0) sub.emplace_back(r, local[i], it.value());
      }
    }
    const auto m = static_cast<Eigen::Index>(region.size());
    Eigen::SparseMatrix<double> a(m, m);
    a.setFromTriplets(sub.begin(), sub.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);
    if (solver.info() != Eigen::Success) {
      return fail("skin weights: the heat system of joint {} could not be factorised", j);
    }
    Eigen::VectorXd rhs(m);
    for (Eigen::Index r = 0; r < m; ++r) {
      const std::uint32_t i = region[static_cast<std::size_t>(r)];
      rhs[r] = static_cast<std::size_t>(labels[i]) == j ? heat[i] : 0.0;
    }
    const Eigen::VectorXd w = solver.solve(rhs);
    for (Eigen::Index r = 0; r < m; ++r) {
      const std::uint32_t i = region[static_cast<std::size_t>(r)];
      weight[i * kSlots + slot_of[static_cast<std::size_t>(r)]] =
          static_cast<float>(std::max(w[r], 0.0));
      local[i] = -1;
    }
  }

  // A few rounds of Jacobi smoothing per joint over the mesh widen transitions that the
  // heat left only an edge or two wide (short bones, fingers); a neighbour that may not
  // depend on the joint counts as 0, so region borders stay at 0.
  {
    std::vector<float> next(weight.size());
    for (int round = 0; round < kSmoothRounds; ++round) {
      for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < kSlots; ++k) {
          const int j = allowed[i][k];
          if (j < 0) continue;
          float sum = 0.0f;
          for (const std::uint32_t nb : ring[i]) {
            for (std::size_t q = 0; q < kSlots; ++q) {
              if (allowed[nb][q] == j) sum += weight[nb * kSlots + q];
            }
          }
          next[i * kSlots + k] =
              0.5f * weight[i * kSlots + k] + 0.5f * sum / static_cast<float>(ring[i].size());
        }
      }
      weight.swap(next);
    }
  }

  // Per vertex: weights below a small share of its total are dropped (by subtraction, so
  // continuously), the rest normalised, largest first.
  SkinWeights out;
  out.joints.assign(n * 4, 0);
  out.weights.assign(n * 4, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    std::array<std::pair<float, int>, kSlots> c;
    float total = 0.0f;
    for (std::size_t k = 0; k < kSlots; ++k) {
      c[k] = {allowed[i][k] >= 0 ? weight[i * kSlots + k] : 0.0f, allowed[i][k]};
      total += c[k].first;
    }
    for (auto& x : c) x.first = std::max(x.first - kFaint * total, 0.0f);
    // Largest first; equal weights ordered by joint index (deterministic).
    std::sort(c.begin(), c.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    float sum = 0.0f;
    for (std::size_t k = 0; k < 4; ++k) sum += c[k].first;
    if (!(sum > 0.0f)) {
      out.joints[i * 4] = static_cast<std::uint16_t>(labels[i]);
      out.weights[i * 4] = 1.0f;
      continue;
    }
    for (std::size_t k = 0; k < 4 && c[k].first > 0.0f; ++k) {
      out.joints[i * 4 + k] = static_cast<std::uint16_t>(c[k].second);
      out.weights[i * 4 + k] = c[k].first / sum;
    }
  }
  return out;
}

}  // namespace vistel::synth
