#include "common/scene/dent_record.hpp"

#include <algorithm>
#include <cmath>

namespace vistel {

void recordDents(std::span<const float> memory, DentRecord& out) {
  out.vertex_count = static_cast<std::uint32_t>(memory.size());
  out.gaps.clear();
  out.depths.clear();
  std::int64_t previous = -1;
  for (std::size_t v = 0; v < memory.size(); ++v) {
    const float m = memory[v];
    if (!(m < 0.0f)) continue;  // no dent (or not finite)
    const float quanta = std::round(-m / kDentQuantumM);
    if (!(quanta >= 1.0f)) continue;  // rounds to no dent
    const auto depth =
        static_cast<std::uint32_t>(std::min(quanta, static_cast<float>(kMaxDentQuanta)));
    out.gaps.push_back(static_cast<std::uint32_t>(static_cast<std::int64_t>(v) - previous - 1));
    out.depths.push_back(depth);
    previous = static_cast<std::int64_t>(v);
  }
}

Status checkDents(std::uint32_t vertex_count, std::span<const std::uint32_t> gaps,
                  std::span<const std::uint32_t> depths, std::size_t max_vertices) {
  if (gaps.size() != depths.size()) {
    return fail("dents: {} vertex gaps but {} depths", gaps.size(), depths.size());
  }
  if (gaps.size() > max_vertices) {
    return fail("dents: {} dented vertices, more than the limit of {}", gaps.size(), max_vertices);
  }
  std::int64_t previous = -1;
  for (std::size_t k = 0; k < gaps.size(); ++k) {
    const std::int64_t v = previous + 1 + static_cast<std::int64_t>(gaps[k]);
    if (v >= static_cast<std::int64_t>(vertex_count)) {
      return fail("dents: entry {} names vertex {} of a skin of {} vertices", k, v, vertex_count);
    }
    if (depths[k] < 1 || depths[k] > kMaxDentQuanta) {
      return fail("dents: entry {} (vertex {}) has depth {} quanta, outside 1..{}", k, v, depths[k],
                  kMaxDentQuanta);
    }
    previous = v;
  }
  return {};
}

Status applyDents(const DentRecord& record, std::span<float> memory) {
  if (record.vertex_count != memory.size()) {
    return fail("dents: a record for {} vertices, the body has {}", record.vertex_count,
                memory.size());
  }
  if (Status st = checkDents(record.vertex_count, record.gaps, record.depths, memory.size()); !st) {
    return st;
  }
  std::fill(memory.begin(), memory.end(), 0.0f);
  std::int64_t previous = -1;
  for (std::size_t k = 0; k < record.gaps.size(); ++k) {
    previous += 1 + static_cast<std::int64_t>(record.gaps[k]);
    memory[static_cast<std::size_t>(previous)] =
        -static_cast<float>(record.depths[k]) * kDentQuantumM;
  }
  return {};
}

}  // namespace vistel
