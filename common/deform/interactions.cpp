// Step 1: sweep-and-prune over primitive bounding volumes with an analytic narrow test.
#include "common/deform/interactions.hpp"

#include <algorithm>
#include <limits>
#include <tuple>

namespace vistel {
namespace {

// The order of pairs: (body_a, prim_a, body_b, prim_b), as one 64-bit key (a function object,
// so that std::sort inlines it).
std::uint64_t pairKey(const Interaction& p) {
  return (std::uint64_t{p.body_a} << 48) | (std::uint64_t{p.prim_a} << 32) |
         (std::uint64_t{p.body_b} << 16) | std::uint64_t{p.prim_b};
}
struct LessPair {
  bool operator()(const Interaction& x, const Interaction& y) const {
    return pairKey(x) < pairKey(y);
  }
};

Interaction ordered(Interaction p) {
  if (std::tie(p.body_b, p.prim_b) < std::tie(p.body_a, p.prim_a)) {
    std::swap(p.body_a, p.body_b);
    std::swap(p.prim_a, p.prim_b);
  }
  return p;
}

bool allowed(std::span<const BodyView> bodies, int ba, int pa, int bb, int pb) {
  const PosedPrimitive& p =
      bodies[static_cast<std::size_t>(ba)].posed->items[static_cast<std::size_t>(pa)];
  const PosedPrimitive& q =
      bodies[static_cast<std::size_t>(bb)].posed->items[static_cast<std::size_t>(pb)];
  if (!p.collides || !q.collides) return false;
  if (ba != bb) return true;
  const CombinationGraph* g = bodies[static_cast<std::size_t>(ba)].graph;
  return pa != pb && g != nullptr && g->collides(pa, pb);
}

}  // namespace

void appendSelfInteractions(const CombinationGraph& graph, const PosedPrimitives& posed,
                            std::uint16_t body, std::vector<Interaction>& pairs) {
  for (const auto& cp : graph.collide_pairs) {
    if (std::max(cp[0], cp[1]) >= posed.items.size()) continue;
    const PosedPrimitive& p = posed.items[cp[0]];
    const PosedPrimitive& q = posed.items[cp[1]];
    if (p.collides && q.collides && boundsOverlap(p, q))
      pairs.push_back({body, cp[0], body, cp[1]});
  }
}

bool boundsOverlap(const PosedPrimitive& p, const PosedPrimitive& q) {
  if (p.bounds.max.x < q.bounds.min.x || q.bounds.max.x < p.bounds.min.x ||
      p.bounds.max.y < q.bounds.min.y || q.bounds.max.y < p.bounds.min.y ||
      p.bounds.max.z < q.bounds.min.z || q.bounds.max.z < p.bounds.min.z) {
    return false;
  }
  return skeletonGap(p.shape, q.shape) <= p.reach + q.reach;
}

void finalizeInteractions(InteractionList& list, int body_count) {
  // Canonical order of the undirected pairs.
  for (Interaction& p : list.pairs) p = ordered(p);
  // Each body's own pairs come in its graph's order, already sorted: most lists need no sort.
  if (!std::is_sorted(list.pairs.begin(), list.pairs.end(), LessPair{})) {
    std::sort(list.pairs.begin(), list.pairs.end(), LessPair{});
  }
  list.pairs.erase(std::unique(list.pairs.begin(), list.pairs.end()), list.pairs.end());
  // Both directions, sorted, with per-body offsets.
  list.directed.clear();
  for (const Interaction& p : list.pairs) {
    list.directed.push_back(p);
    list.directed.push_back(Interaction{p.body_b, p.prim_b, p.body_a, p.prim_a});
  }
  std::sort(list.directed.begin(), list.directed.end(), LessPair{});
  list.body_offsets.assign(static_cast<std::size_t>(body_count) + 1, 0);
  for (const Interaction& d : list.directed) {
    if (d.body_a < body_count) ++list.body_offsets[static_cast<std::size_t>(d.body_a) + 1];
  }
  for (std::size_t b = 0; b < static_cast<std::size_t>(body_count); ++b) {
    list.body_offsets[b + 1] += list.body_offsets[b];
  }
}

namespace {

bool boxesMeet(const Bounds& a, const Bounds& b) {
  return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y &&
         a.min.z <= b.max.z && b.min.z <= a.max.z;
}

// The collidable primitives of a body whose boxes meet `region`.
void primitivesIn(const PosedPrimitives& posed, const Bounds& region,
                  std::vector<std::uint16_t>& out) {
  out.clear();
  for (std::size_t i = 0; i < posed.items.size(); ++i) {
    const PosedPrimitive& p = posed.items[i];
    if (p.collides && boxesMeet(p.bounds, region)) out.push_back(static_cast<std::uint16_t>(i));
  }
}

}  // namespace

void buildInteractions(std::span<const BodyView> bodies, InteractionScratch& s,
                       InteractionList& out, bool self_contact) {
  out.pairs.clear();
  const std::size_t n = bodies.size();

  // Each body's own pairs, and its box.
  s.body_boxes.resize(n);
  s.body_live.assign(n, 0);
  for (std::size_t b = 0; b < n; ++b) {
    const PosedPrimitives& posed = *bodies[b].posed;
    Bounds box{glm::vec3(std::numeric_limits<float>::max()),
               glm::vec3(std::numeric_limits<float>::lowest())};
    for (const PosedPrimitive& p : posed.items) {
      if (!p.collides) continue;
      box.min = glm::min(box.min, p.bounds.min);
      box.max = glm::max(box.max, p.bounds.max);
      s.body_live[b] = 1;
    }
    s.body_boxes[b] = box;
    if (bodies[b].graph != nullptr && self_contact) {
      appendSelfInteractions(*bodies[b].graph, posed, static_cast<std::uint16_t>(b), out.pairs);
    }
  }

  // Bodies by their boxes' min x: last frame's order when the set is the same (insertion
  // sort is then nearly linear), else sorted afresh.
  const auto key_less = [&s](std::uint32_t x, std::uint32_t y) {
    const float kx = s.body_boxes[x].min.x;
    const float ky = s.body_boxes[y].min.x;
    return kx < ky || (kx == ky && x < y);
  };
  std::size_t live = 0;
  for (std::size_t b = 0; b < n; ++b) live += s.body_live[b];
  bool same = s.body_order.size() == live;
  for (std::size_t k = 0; same && k < s.body_order.size(); ++k) {
    same = s.body_order[k] < n && s.body_live[s.body_order[k]] != 0;
  }
  if (!same) {
    s.body_order.clear();
    for (std::size_t b = 0; b < n; ++b) {
      if (s.body_live[b] != 0) s.body_order.push_back(static_cast<std::uint32_t>(b));
    }
    std::sort(s.body_order.begin(), s.body_order.end(), key_less);
  } else {
    for (std::size_t i = 1; i < s.body_order.size(); ++i) {
      const std::uint32_t x = s.body_order[i];
      std::size_t j = i;
      while (j > 0 && key_less(x, s.body_order[j - 1])) {
        s.body_order[j] = s.body_order[j - 1];
        --j;
      }
      s.body_order[j] = x;
    }
  }

  // Sweep over the bodies; a pair whose boxes meet tests the primitives of each that lie
  // in the common box against each other.
  s.active.clear();
  for (const std::uint32_t a : s.body_order) {
    const Bounds& box_a = s.body_boxes[a];
    std::size_t keep = 0;
    for (std::size_t k = 0; k < s.active.size(); ++k) {
      const std::uint32_t b = s.active[k];
      const Bounds& box_b = s.body_boxes[b];
      if (box_b.max.x < box_a.min.x) continue;  // closed for good
      s.active[keep++] = b;
      if (!boxesMeet(box_a, box_b)) continue;
      const Bounds common{glm::max(box_a.min, box_b.min), glm::min(box_a.max, box_b.max)};
      const PosedPrimitives& pa = *bodies[a].posed;
      const PosedPrimitives& pb = *bodies[b].posed;
      primitivesIn(pa, common, s.near_a);
      if (s.near_a.empty()) continue;
      primitivesIn(pb, common, s.near_b);
      for (const std::uint16_t i : s.near_a) {
        for (const std::uint16_t j : s.near_b) {
          if (boundsOverlap(pa.items[i], pb.items[j])) {
            out.pairs.push_back(
                {static_cast<std::uint16_t>(a), i, static_cast<std::uint16_t>(b), j});
          }
        }
      }
    }
    s.active.resize(keep);
    s.active.push_back(a);
  }
  finalizeInteractions(out, static_cast<int>(n));
}

void buildInteractions(const CombinationGraph& graph, const PosedPrimitives& posed,
                       InteractionList& out) {
  out.pairs.clear();
  appendSelfInteractions(graph, posed, 0, out.pairs);
  finalizeInteractions(out, 1);
}

Status validateInteractions(const InteractionList& list, std::span<const BodyView> bodies) {
  for (std::size_t i = 0; i < list.pairs.size(); ++i) {
    const Interaction& p = list.pairs[i];
    const auto prim_ok = [&](std::uint16_t b, std::uint16_t prim) {
      return b < bodies.size() && bodies[b].posed != nullptr &&
             prim < bodies[b].posed->items.size();
    };
    if (!prim_ok(p.body_a, p.prim_a) || !prim_ok(p.body_b, p.prim_b)) {
      return fail("interaction {}: body or primitive out of range", i);
    }
    if (p.body_a == p.body_b && p.prim_a == p.prim_b) {
      return fail("interaction {}: a primitive paired with itself", i);
    }
    if (!allowed(bodies, p.body_a, p.prim_a, p.body_b, p.prim_b)) {
      return fail("interaction {}: pair not allowed to collide", i);
    }
  }
  return {};
}

}  // namespace vistel
