// The shared room's collision world in a snapshot (proto/WIRE.md §3.7, §3.8): prop states
// (a ball's centre and velocity) and the interaction list of Step 1 (which primitives of
// which bodies touch this tick), as the server computed them. Each has one serialize
// function used to read, write and measure it.
//
// Interaction pairs name bodies by index into the section's own body table (member ids,
// then prop ids) and primitives by their index in the body's PrimitiveSet (12 bits: below
// kMaxPrimitives = 4096). Pairs are bit-packed: 2 w + 24 bits with w = the bits of the
// largest body index (at least 1), then zero padding to a byte.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "common/wire/bit_stream.hpp"

namespace vistel::wire {

inline constexpr int kPropStateBytes = 16;
inline constexpr int kPrimIndexBits = 12;                  // primitive index (< 4096)
inline constexpr int kMaxSectionBodies = 255;              // members + props in one body table
inline constexpr int kInteractionSectionHeader = 5;        // flags, m, q, then u16 count after ids
inline constexpr std::uint8_t kInteractionsTruncated = 1;  // flags bit 0
// flags bit 1: the section lists only pairs between bodies; each receiver computes the
// self-contact pairs of the bodies it deforms from its own poses (WIRE.md §3.8).
inline constexpr std::uint8_t kInteractionsSelfOmitted = 2;
inline constexpr float kPropPositionUnit = 0.001f;  // metres per position unit
inline constexpr float kPropVelocityUnit = 0.001f;  // m/s per velocity unit

// One prop's state at the snapshot's tick (16 bytes). Room space: metres, +Y up.
struct PropStateRecord {
  std::uint32_t prop_id = 0;
  std::array<std::int16_t, 3> position_mm{};    // centre, millimetres (clamped to +-32.767 m)
  std::array<std::int16_t, 3> velocity_mm_s{};  // mm/s (clamped to +-32.767 m/s)
};

template <typename Stream>
bool serialize(Stream& s, PropStateRecord& p) {
  if (!serializeU32(s, p.prop_id)) return false;
  for (std::int16_t& c : p.position_mm) {
    if (!serializeI16(s, c)) return false;
  }
  for (std::int16_t& c : p.velocity_mm_s) {
    if (!serializeI16(s, c)) return false;
  }
  return true;
}

// Quantizes (non-finite components become 0, the rest are rounded and clamped).
PropStateRecord encodePropState(std::uint32_t prop_id, const glm::vec3& position,
                                const glm::vec3& velocity);
glm::vec3 propPosition(const PropStateRecord& p);
glm::vec3 propVelocity(const PropStateRecord& p);

// One touching pair: (body index, primitive index) twice, indices into the section's
// body table.
struct WirePair {
  std::uint8_t body_a = 0;
  std::uint16_t prim_a = 0;  // < 4096
  std::uint8_t body_b = 0;
  std::uint16_t prim_b = 0;

  friend bool operator==(const WirePair&, const WirePair&) = default;
};

struct InteractionSection {
  std::uint8_t flags = 0;                 // kInteractionsTruncated: the server had more
                                          // pairs than it sent (self-contact dropped first)
  std::vector<std::uint32_t> member_ids;  // body table part 1 (m <= 255)
  std::vector<std::uint32_t> prop_ids;    // body table part 2 (m + q <= 255)
  std::vector<WirePair> pairs;            // (count <= 65535)

  int bodyCount() const { return static_cast<int>(member_ids.size() + prop_ids.size()); }
  void clear() {
    flags = 0;
    member_ids.clear();
    prop_ids.clear();
    pairs.clear();
  }
};

// Bits per body index for a table of n bodies: max(1, bit width of n - 1).
constexpr int bodyIndexBits(int body_count) {
  return body_count <= 2 ? 1
                         : static_cast<int>(std::bit_width(static_cast<unsigned>(body_count - 1)));
}

// Bytes of a section with this many bodies and pairs.
constexpr std::size_t interactionSectionBytes(int body_count, std::size_t pair_count) {
  const std::size_t pair_bits = 2u * static_cast<std::size_t>(bodyIndexBits(body_count)) +
                                2u * static_cast<std::size_t>(kPrimIndexBits);
  return static_cast<std::size_t>(kInteractionSectionHeader) +
         4u * static_cast<std::size_t>(body_count) + (pair_count * pair_bits + 7) / 8;
}

// Reading checks every count against the bytes left before sizing a vector, body indices
// against the table, flags against the defined bits, and zero padding.
template <typename Stream>
bool serialize(Stream& s, InteractionSection& x) {
  std::uint8_t m = static_cast<std::uint8_t>(x.member_ids.size());
  std::uint8_t q = static_cast<std::uint8_t>(x.prop_ids.size());
  if (!serializeU8(s, x.flags) || !serializeU8(s, m) || !serializeU8(s, q)) return false;
  if constexpr (Stream::kReading) {
    if ((x.flags & ~(kInteractionsTruncated | kInteractionsSelfOmitted)) != 0) return false;
    if (m + q > kMaxSectionBodies || static_cast<std::size_t>(m + q) > s.bitsLeft() / 32) {
      return false;
    }
    x.member_ids.resize(m);
    x.prop_ids.resize(q);
  }
  for (std::uint32_t& id : x.member_ids) {
    if (!serializeU32(s, id)) return false;
  }
  for (std::uint32_t& id : x.prop_ids) {
    if (!serializeU32(s, id)) return false;
  }
  std::uint16_t count = static_cast<std::uint16_t>(x.pairs.size());
  if (!serializeU16(s, count)) return false;
  const int bodies = m + q;
  const int w = bodyIndexBits(bodies);
  if constexpr (Stream::kReading) {
    if (count > 0 && bodies == 0) return false;
    if (count > s.bitsLeft() / static_cast<std::size_t>(2 * w + 2 * kPrimIndexBits)) return false;
    x.pairs.resize(count);
  }
  const auto max_body = static_cast<std::uint32_t>(bodies > 0 ? bodies - 1 : 0);
  for (WirePair& p : x.pairs) {
    std::uint32_t ba = p.body_a, pa = p.prim_a, bb = p.body_b, pb = p.prim_b;
    if (!serializeBounded(s, ba, w, max_body) || !s.bits(pa, kPrimIndexBits) ||
        !serializeBounded(s, bb, w, max_body) || !s.bits(pb, kPrimIndexBits)) {
      return false;
    }
    p.body_a = static_cast<std::uint8_t>(ba);
    p.prim_a = static_cast<std::uint16_t>(pa);
    p.body_b = static_cast<std::uint8_t>(bb);
    p.prim_b = static_cast<std::uint16_t>(pb);
  }
  return s.align();
}

}  // namespace vistel::wire
