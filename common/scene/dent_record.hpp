// A body's elastic memory as it travels between sites (proto/SESSION.md §2.5 "Dents"):
// the dents its plastic and viscoelastic parts keep (DeformState::memory, metres, <= 0),
// sparse and quantised, so that every site draws the same dent on the same body, and a
// scene rebuilt or joined late starts from it.
//
// The wire form is the protobuf Dents message's: dented vertices in increasing order, each
// given by its gap from the previous one (index - previous - 1; the first one's gap is its
// index), and each vertex's depth in whole quanta of kDentQuantumM (>= 1). A vertex whose
// memory rounds to no quantum is left out, so a body whose dents have recovered sends an
// empty record. Pure and allocation-free once the vectors have grown.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "common/base/result.hpp"

namespace vistel {

inline constexpr float kDentQuantumM = 1e-4f;            // 0.1 mm
inline constexpr std::uint32_t kMaxDentQuanta = 10'000;  // 1 m: deeper is not a dent

struct DentRecord {
  std::uint32_t vertex_count = 0;     // of the body's skin (a receiver checks its own)
  std::vector<std::uint32_t> gaps;    // per dented vertex, in increasing vertex order
  std::vector<std::uint32_t> depths;  // quanta, 1..kMaxDentQuanta, same length
  friend bool operator==(const DentRecord&, const DentRecord&) = default;
};

// The record of a state's memory (one float per vertex; positive or non-finite entries,
// which memory never holds, are left out; depths past kMaxDentQuanta are clamped).
void recordDents(std::span<const float> memory, DentRecord& out);

// Whether a wire record is well formed: as many gaps as depths, at most max_vertices of
// them, every vertex inside vertex_count, every depth within 1..kMaxDentQuanta. The error
// says what and which entry. O(entries), no allocation.
Status checkDents(std::uint32_t vertex_count, std::span<const std::uint32_t> gaps,
                  std::span<const std::uint32_t> depths, std::size_t max_vertices);

// Writes a record into a body's memory (every vertex: zero where the record has no dent).
// Fails, changing nothing, when the record is malformed or is for another vertex count.
Status applyDents(const DentRecord& record, std::span<float> memory);

// Dented vertices in a record.
inline std::size_t dentCount(const DentRecord& record) { return record.depths.size(); }

}  // namespace vistel
