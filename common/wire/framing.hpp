// Length framing for the TCP control channel (proto/WIRE.md §2): each frame is a u32
// little-endian payload length followed by that many bytes (one protobuf message).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace vistel::wire {

inline constexpr std::size_t kFrameHeaderBytes = 4;

// Appends one frame (header + payload) to out.
void appendFrame(std::span<const std::uint8_t> payload, std::vector<std::uint8_t>& out);

// Reassembles frames from a byte stream that arrives in arbitrary pieces. A length
// above max_frame_bytes breaks the stream as soon as its 4 header bytes arrive (the
// payload is never buffered): the caller drops the peer. Memory stays below about
// max_frame_bytes + 4 + the largest single push.
class FrameDecoder {
 public:
  explicit FrameDecoder(std::size_t max_frame_bytes) : max_frame_bytes_(max_frame_bytes) {}

  // Adds received bytes. False once the stream is broken (then error() says why).
  bool push(std::span<const std::uint8_t> bytes);
  // The next complete frame's payload, or nullopt (need more bytes, or broken). The
  // span stays valid until the next push().
  std::optional<std::span<const std::uint8_t>> next();

  bool broken() const { return !error_.empty(); }
  const std::string& error() const { return error_; }
  // Bytes received but not yet returned as frames.
  std::size_t buffered() const { return buffer_.size() - read_pos_; }

 private:
  bool checkHeader();

  std::size_t max_frame_bytes_;
  std::vector<std::uint8_t> buffer_;
  std::size_t read_pos_ = 0;
  std::string error_;
};

}  // namespace vistel::wire
