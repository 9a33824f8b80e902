#include "offline/synthesize/shared_rim.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vistel {
namespace {

struct Entry {
  std::uint32_t index = 0;
  glm::vec3 position{0.0f};
  glm::vec3 normal{0.0f};
  int label = 0;
};

struct Run {
  std::size_t first = 0, last = 0;  // inclusive, in the rotated rim
  int label = 0;
};

// Rotates `w` to start where a run starts and lists its runs (one run when one label).
std::vector<Run> runs(std::vector<Entry>& w) {
  const std::size_t n = w.size();
  std::size_t start = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (w[i].label != w[(i + n - 1) % n].label) {
      start = i;
      break;
    }
  }
  if (start == n) return {{0, n - 1, w[0].label}};
  std::rotate(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(start), w.end());
  std::vector<Run> out;
  for (std::size_t i = 0; i < n; ++i) {
    if (i == 0 || w[i].label != w[i - 1].label) out.push_back({i, i, w[i].label});
    out.back().last = i;
  }
  return out;
}

}  // namespace

SharedRimSplit splitSharedRim(const RimCurve& rim, std::span<const RimCurve* const> children,
                              std::span<const PartField* const> child_fields,
                              std::uint32_t first_new_vertex, float spacing) {
  SharedRimSplit out;
  out.pieces.resize(children.size());
  const std::size_t n = rim.index.size();

  // 1. Labels: the nearest child rim.
  std::vector<Entry> w(n);
  for (std::size_t i = 0; i < n; ++i) {
    w[i] = {rim.index[i], rim.position[i], rim.normal[i], 0};
    float best = std::numeric_limits<float>::max();
    for (std::size_t c = 0; c < children.size(); ++c) {
      for (const glm::vec3& q : children[c]->position) {
        const float d = glm::distance(q, rim.position[i]);
        if (d < best) {
          best = d;
          w[i].label = static_cast<int>(c);
        }
      }
    }
  }
  // Short runs join their predecessor.
  for (int round = 0; round < 64; ++round) {
    const std::vector<Run> r = runs(w);
    if (r.size() <= 1) break;
    bool changed = false;
    for (std::size_t k = 0; k < r.size() && !changed; ++k) {
      if (r[k].last - r[k].first + 1 >= 3) continue;
      const int previous = r[(k + r.size() - 1) % r.size()].label;
      for (std::size_t i = r[k].first; i <= r[k].last; ++i) w[i].label = previous;
      changed = true;
    }
    if (!changed) break;
  }

  // 2. Clip children off one run at a time.
  for (std::size_t guard = 0; guard < 4 * children.size() + 8; ++guard) {
    std::vector<Run> r = runs(w);
    if (r.size() <= 1) break;
    std::vector<int> count(children.size(), 0);
    for (const Run& run : r) ++count[static_cast<std::size_t>(run.label)];
    // The leaf: a label with one run; else the longest run of the label with fewest runs,
    // its other runs given to their predecessors.
    std::size_t leaf = r.size();
    for (std::size_t k = 0; k < r.size() && leaf == r.size(); ++k) {
      if (count[static_cast<std::size_t>(r[k].label)] == 1) leaf = k;
    }
    if (leaf == r.size()) {
      int fewest = -1;
      for (std::size_t c = 0; c < count.size(); ++c) {
        if (count[c] > 0 && (fewest < 0 || count[c] < count[static_cast<std::size_t>(fewest)]))
          fewest = static_cast<int>(c);
      }
      std::size_t longest = 0, best_len = 0;
      for (std::size_t k = 0; k < r.size(); ++k) {
        if (r[k].label == fewest && r[k].last - r[k].first + 1 > best_len) {
          best_len = r[k].last - r[k].first + 1;
          longest = k;
        }
      }
      for (std::size_t k = 0; k < r.size(); ++k) {
        if (r[k].label != fewest || k == longest) continue;
        const int previous = r[(k + r.size() - 1) % r.size()].label;
        for (std::size_t i = r[k].first; i <= r[k].last; ++i) w[i].label = previous;
      }
      continue;
    }
    const Run run = r[leaf];
    const int next_label = r[(leaf + 1) % r.size()].label;
    const int previous_label = r[(leaf + r.size() - 1) % r.size()].label;
    const Entry& head = w[run.first];
    const Entry& tail = w[run.last];

    // 3. The chord from the run's end back to its start, between the two children.
    const PartField& fa = *child_fields[static_cast<std::size_t>(run.label)];
    const PartField& fb = *child_fields[static_cast<std::size_t>(next_label)];
    const float length = glm::distance(tail.position, head.position);
    const int interior = std::max(0, static_cast<int>(std::lround(length / spacing)) - 1);
    std::vector<Entry> chord;
    for (int i = 1; i <= interior; ++i) {
      const float t = static_cast<float>(i) / static_cast<float>(interior + 1);
      glm::vec3 x = glm::mix(tail.position, head.position, t);
      // Between the nearest points of the two children: on the Hermite curve leaving each
      // along its surface (a midpoint would cut under a convex surface), a few times over.
      glm::vec3 g(0.0f);
      for (int iter = 0; iter < 4; ++iter) {
        const FieldSample sa = fa.at(x), sb = fb.at(x);
        const glm::vec3 d = sb.point - sa.point;
        // d in each tangent plane, as long as d.
        const auto along = [&](const glm::vec3& normal) {
          const glm::vec3 tangent = d - glm::dot(d, normal) * normal;
          const float len = glm::length(tangent);
          return len > 1e-9f ? tangent * (glm::length(d) / len) : d;
        };
        x = 0.5f * (sa.point + sb.point) + 0.125f * (along(sa.normal) - along(sb.normal));
        g = sa.normal + sb.normal;
      }
      const float gl = glm::length(g);
      ChordVertex cv;
      cv.position = x;
      cv.normal = gl > 0.0f ? g / gl : glm::mix(tail.normal, head.normal, t);
      cv.from = tail.index;
      cv.to = head.index;
      cv.t = t;
      const auto index = first_new_vertex + static_cast<std::uint32_t>(out.chords.size());
      out.chords.push_back(cv);
      chord.push_back({index, cv.position, cv.normal, previous_label});
    }

    // The leaf's piece: its run, then the chord back to the start.
    RimCurve& piece = out.pieces[static_cast<std::size_t>(run.label)];
    for (std::size_t i = run.first; i <= run.last; ++i) {
      piece.index.push_back(w[i].index);
      piece.position.push_back(w[i].position);
      piece.normal.push_back(w[i].normal);
    }
    for (const Entry& e : chord) {
      piece.index.push_back(e.index);
      piece.position.push_back(e.position);
      piece.normal.push_back(e.normal);
    }
    // The rest goes on along the chord the other way; the run's ends stay in it.
    std::vector<Entry> rest(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(run.first));
    Entry a = head, b = tail;
    a.label = b.label = previous_label;
    rest.push_back(a);
    for (auto it = chord.rbegin(); it != chord.rend(); ++it) rest.push_back(*it);
    if (run.last != run.first) rest.push_back(b);
    rest.insert(rest.end(), w.begin() + static_cast<std::ptrdiff_t>(run.last + 1), w.end());
    w = std::move(rest);
  }

  // The last label keeps what is left.
  if (!w.empty()) {
    RimCurve& piece = out.pieces[static_cast<std::size_t>(w[0].label)];
    if (piece.index.empty()) {
      for (const Entry& e : w) {
        piece.index.push_back(e.index);
        piece.position.push_back(e.position);
        piece.normal.push_back(e.normal);
      }
    }
  }
  return out;
}

}  // namespace vistel
