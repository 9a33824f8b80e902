// Sealed datagrams for tests that drive a Room (or the server core) directly, playing its
// members' clients (proto/WIRE.md §3.9): fixed per-member keys, a process-wide increasing
// counter (fresh for every replay window), and opening of what the room sends.
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "common/wire/datagram_crypto.hpp"
#include "common/wire/packets.hpp"
#include "server/core/effects.hpp"

namespace vistel::test {

// Deterministic keys of a member a test adds with kAddMember.
inline wire::AeadKey uplinkKeyOf(std::uint32_t member) {
  wire::AeadKey k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(member * 7u + i);
  return k;
}
inline wire::AeadKey downlinkKeyOf(std::uint32_t member) {
  wire::AeadKey k{};
  for (std::size_t i = 0; i < k.size(); ++i) k[i] = static_cast<std::uint8_t>(member * 13u + 3 * i);
  return k;
}

// Sets an AddMember command's keys to the member's test keys.
inline void setTestKeys(server::RoomCommand& c) {
  c.uplink_key = uplinkKeyOf(c.member.value);
  c.downlink_key = downlinkKeyOf(c.member.value);
}

// A counter never used before in this process.
inline std::uint64_t nextTestCounter() {
  static std::atomic<std::uint64_t> counter{1};
  return counter++;
}

// Seals a client -> server plain datagram with a key and a counter (default: fresh).
inline std::vector<std::uint8_t> sealWith(const wire::AeadKey& key, std::vector<std::uint8_t> plain,
                                          std::uint64_t counter = 0) {
  wire::sealDatagram(key, counter != 0 ? counter : nextTestCounter(), wire::kClientHeaderBytes,
                     plain);
  return plain;
}

// Seals a plain client datagram as member `member` (its test uplink key).
inline std::vector<std::uint8_t> sealAs(std::uint32_t member, std::vector<std::uint8_t> plain) {
  return sealWith(uplinkKeyOf(member), std::move(plain));
}

// Opens a server -> client datagram with a key: the plain layout, or empty when it does
// not verify.
inline std::vector<std::uint8_t> openWith(const wire::AeadKey& key,
                                          std::vector<std::uint8_t> sealed) {
  std::uint64_t counter = 0;
  std::size_t plain_size = 0;
  if (!wire::openDatagram(key, wire::kServerHeaderBytes, sealed, counter, plain_size)) return {};
  sealed.resize(plain_size);
  return sealed;
}

// Opens what the room sent to member `member` (its test downlink key).
inline std::vector<std::uint8_t> openFor(std::uint32_t member, std::vector<std::uint8_t> sealed) {
  return openWith(downlinkKeyOf(member), std::move(sealed));
}

}  // namespace vistel::test
