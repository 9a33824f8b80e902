// Test members of a server Room without a network: member i has id 0x10000 + i, sends from
// loopback port kSeatedPortBase + i, sits at the default layout's seat i and has the test
// keys of sealed_datagrams.hpp.
#pragma once

#include <cstdint>
#include <tuple>
#include <utility>

#include "common/scene/seat_layout.hpp"
#include "common/wire/endpoint.hpp"
#include "server/core/room.hpp"
#include "tests/server/sealed_datagrams.hpp"

namespace vistel::test {

inline constexpr int kSeatedPortBase = 20000;
inline constexpr int kSeatedJoints = 5;  // joints of every seated member's avatar

inline std::uint32_t seatedMemberId(int i) { return 0x00010000u + static_cast<std::uint32_t>(i); }

inline wire::Endpoint seatedEndpoint(int i) {
  return wire::Endpoint::ipv4(0x7F000001u, static_cast<std::uint16_t>(kSeatedPortBase + i));
}

// Adds and binds members 0..n-1 at time 0.
inline void seatMembers(server::Room& room, int n) {
  for (int i = 0; i < n; ++i) {
    server::RoomCommand c;
    c.kind = server::RoomCommand::Kind::kAddMember;
    c.room = room.id();
    c.member = server::MemberId{seatedMemberId(i)};
    setTestKeys(c);
    c.seat = seatPlacement(i, SeatLayout{});
    c.joint_count = kSeatedJoints;
    room.apply(c, 0.0);
    c.kind = server::RoomCommand::Kind::kBindEndpoint;
    c.endpoint = seatedEndpoint(i);
    room.apply(c, 0.0);
  }
}

// A collision pair named by ids, ends ordered: ((is_prop, id, prim), (is_prop, id, prim)).
using PairEnd = std::tuple<bool, std::uint32_t, std::uint16_t>;
using IdPair = std::pair<PairEnd, PairEnd>;

inline IdPair orderedPair(PairEnd a, PairEnd b) { return a < b ? IdPair{a, b} : IdPair{b, a}; }

}  // namespace vistel::test
