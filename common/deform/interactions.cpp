// Step 1: sweep-and-prune over primitive bounding volumes with an analytic narrow test.
#include "common/deform/interactions.hpp"

#include <algorithm>
#include <tuple>

namespace vistel {
namespace {

bool lessPair(const Interaction& x, const Interaction& y) {
  return std::tie(x.body_a, x.prim_a, x.body_b, x.prim_b) <
         std::tie(y.body_a, y.prim_a, y.body_b, y.prim_b);
}

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
  std::sort(list.pairs.begin(), list.pairs.end(), lessPair);
  list.pairs.erase(std::unique(list.pairs.begin(), list.pairs.end()), list.pairs.end());
  // Both directions, sorted, with per-body offsets.
  list.directed.clear();
  for (const Interaction& p : list.pairs) {
    list.directed.push_back(p);
    list.directed.push_back(Interaction{p.body_b, p.prim_b, p.body_a, p.prim_a});
  }
  std::sort(list.directed.begin(), list.directed.end(), lessPair);
  list.body_offsets.assign(static_cast<std::size_t>(body_count) + 1, 0);
  for (const Interaction& d : list.directed) {
    if (d.body_a < body_count) ++list.body_offsets[static_cast<std::size_t>(d.body_a) + 1];
  }
  for (std::size_t b = 0; b < static_cast<std::size_t>(body_count); ++b) {
    list.body_offsets[b + 1] += list.body_offsets[b];
  }
}

void buildInteractions(std::span<const BodyView> bodies, InteractionScratch& s,
                       InteractionList& out) {
  // Gather every collidable primitive's x interval.
  s.items.clear();
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const PosedPrimitives& posed = *bodies[b].posed;
    for (std::size_t i = 0; i < posed.items.size(); ++i) {
      const PosedPrimitive& p = posed.items[i];
      if (!p.collides) continue;
      s.items.push_back({p.bounds.min.x, p.bounds.max.x, static_cast<std::uint16_t>(b),
                         static_cast<std::uint16_t>(i)});
    }
  }
  // Keep last frame's order when the item set is unchanged (insertion sort is then
  // nearly linear); otherwise sort afresh.
  const auto key_less = [&s](std::uint32_t x, std::uint32_t y) {
    const float kx = s.items[x].min_x;
    const float ky = s.items[y].min_x;
    return kx < ky || (kx == ky && x < y);
  };
  if (s.order.size() != s.items.size()) {
    s.order.resize(s.items.size());
    for (std::size_t i = 0; i < s.order.size(); ++i) s.order[i] = static_cast<std::uint32_t>(i);
    std::sort(s.order.begin(), s.order.end(), key_less);
  } else {
    for (std::size_t i = 1; i < s.order.size(); ++i) {
      const std::uint32_t x = s.order[i];
      std::size_t j = i;
      while (j > 0 && key_less(x, s.order[j - 1])) {
        s.order[j] = s.order[j - 1];
        --j;
      }
      s.order[j] = x;
    }
  }
  // Sweep: each item against the open intervals that reach its start.
  out.pairs.clear();
  s.active.clear();
  for (const std::uint32_t idx : s.order) {
    const auto& it = s.items[idx];
    std::size_t keep = 0;
    for (std::size_t k = 0; k < s.active.size(); ++k) {
      const auto& other = s.items[s.active[k]];
      if (other.max_x < it.min_x) continue;  // closed for good
      s.active[keep++] = s.active[k];
      if (!allowed(bodies, it.body, it.prim, other.body, other.prim)) continue;
      const PosedPrimitive& p = bodies[it.body].posed->items[it.prim];
      const PosedPrimitive& q = bodies[other.body].posed->items[other.prim];
      if (boundsOverlap(p, q)) out.pairs.push_back({it.body, it.prim, other.body, other.prim});
    }
    s.active.resize(keep);
    s.active.push_back(idx);
  }
  finalizeInteractions(out, static_cast<int>(bodies.size()));
}

void buildInteractions(const CombinationGraph& graph, const PosedPrimitives& posed,
                       InteractionList& out) {
  out.pairs.clear();
  for (const auto& cp : graph.collide_pairs) {
    const PosedPrimitive& p = posed.items[cp[0]];
    const PosedPrimitive& q = posed.items[cp[1]];
    if (p.collides && q.collides && boundsOverlap(p, q)) out.pairs.push_back({0, cp[0], 0, cp[1]});
  }
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
