// Disjoint sets (union-find) over the ids 0..n-1: connected components of meshes (the skin's
// pieces, inner layers, the polygonizer's largest piece). Path halving; each set's root is
// its smallest id, so roots, and whatever is numbered in their order, do not depend on the
// order of the joins. Cost: near-constant per operation (amortised); n ids of 4 bytes.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <vector>

namespace vistel {

class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
  }

  // The root (smallest id) of x's set.
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }

  // Merges the sets of a and b.
  void join(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::uint32_t> parent_;
};

}  // namespace vistel
