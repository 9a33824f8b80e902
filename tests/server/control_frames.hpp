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
  return msg;
}

}  // namespace vistel::test
