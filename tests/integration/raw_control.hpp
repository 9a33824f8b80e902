// A raw TCP control connection to a vistel-server on loopback, for integration tests that
// play a misbehaving or minimal peer: connect, send ClientMessages in frames, read the
// first ServerMessage back. Plain POSIX sockets; failures are reported, never thrown.
#pragma once

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "common/wire/framing.hpp"
#include "control.pb.h"

namespace vistel::test {

// A connected socket to 127.0.0.1:port (receive_buffer > 0 sets SO_RCVBUF first), or -1.
inline int connectLoopback(std::uint16_t port, int receive_buffer = 0) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  if (receive_buffer > 0) {
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
  }
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// One framed ClientMessage; false when the connection would not take it all.
inline bool sendControl(int fd, const control::ClientMessage& msg) {
  const std::string payload = msg.SerializeAsString();
  std::vector<std::uint8_t> frame;
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()), frame);
  return ::send(fd, frame.data(), frame.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(frame.size());
}

// The first ServerMessage that arrives within timeout_s (it must come in one read), or
// nullopt.
inline std::optional<control::ServerMessage> receiveControl(int fd, int timeout_s) {
  timeval timeout{timeout_s, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::vector<std::uint8_t> got(1 << 16);
  const ssize_t n = ::recv(fd, got.data(), got.size(), 0);
  if (n <= 4) return std::nullopt;
  wire::FrameDecoder decoder(1u << 20);
  if (!decoder.push(std::span(got.data(), static_cast<std::size_t>(n)))) return std::nullopt;
  auto reply = decoder.next();
  if (!reply) return std::nullopt;
  control::ServerMessage answer;
  if (!answer.ParseFromArray(reply->data(), static_cast<int>(reply->size()))) return std::nullopt;
  return answer;
}

// A Join of protocol version 5 for room `room` with an avatar of this hash and size.
inline control::ClientMessage joinRequest(const std::string& room, const std::string& name,
                                          const std::string& hash, std::uint64_t size) {
  control::ClientMessage msg;
  control::Join& join = *msg.mutable_join();
  join.set_protocol_version(5);
  // A valid X25519 public key (RFC 7748 §6.1, Alice's): these joins never use UDP.
  join.set_udp_public_key(std::string{
      '\x85', '\x20', '\xf0', '\x09', '\x89', '\x30', '\xa7', '\x54', '\x74', '\x8b', '\x7d',
      '\xdc', '\xb4', '\x3e', '\xf7', '\x5a', '\x0d', '\xbf', '\x3a', '\x0d', '\x26', '\x38',
      '\x1a', '\xf4', '\xeb', '\xa4', '\xa9', '\x8e', '\xaa', '\x9b', '\x4e', '\x6a'});
  join.set_room(room);
  join.set_name(name);
  join.set_avatar_hash(hash);
  join.set_avatar_size(size);
  return msg;
}

}  // namespace vistel::test
