// Raw control-channel traffic for tests that play a misbehaving peer: frames of
// ClientMessages, and the ServerMessages in what a raw connection received.
#pragma once

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/wire/framing.hpp"
#include "control.pb.h"

namespace vistel::test {

inline std::vector<std::uint8_t> frameOf(const control::ClientMessage& msg) {
  const std::string payload = msg.SerializeAsString();
  std::vector<std::uint8_t> out;
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()), out);
  return out;
}

inline std::vector<control::ServerMessage> messagesOf(const std::vector<std::uint8_t>& bytes) {
  wire::FrameDecoder d(1u << 24);
  EXPECT_TRUE(d.push(bytes));
  std::vector<control::ServerMessage> out;
  while (auto f = d.next()) {
    control::ServerMessage m;
    EXPECT_TRUE(m.ParseFromArray(f->data(), static_cast<int>(f->size())));
    out.push_back(m);
  }
  return out;
}

// A valid X25519 public key (RFC 7748 §6.1, Alice's) for joins that never use UDP.
inline const std::string kTestUdpPublicKey = {
    '\x85', '\x20', '\xf0', '\x09', '\x89', '\x30', '\xa7', '\x54', '\x74', '\x8b', '\x7d',
    '\xdc', '\xb4', '\x3e', '\xf7', '\x5a', '\x0d', '\xbf', '\x3a', '\x0d', '\x26', '\x38',
    '\x1a', '\xf4', '\xeb', '\xa4', '\xa9', '\x8e', '\xaa', '\x9b', '\x4e', '\x6a'};

inline control::ClientMessage joinMessage(const std::string& room, const std::string& name,
                                          const std::string& hash, std::uint64_t size,
                                          std::uint32_t version) {
  control::ClientMessage msg;
  control::Join& j = *msg.mutable_join();
  j.set_protocol_version(version);
  j.set_room(room);
  j.set_name(name);
  j.set_avatar_hash(hash);
  j.set_avatar_size(size);
  j.set_udp_public_key(kTestUdpPublicKey);
  return msg;
}

}  // namespace vistel::test
