#include "common/wire/framing.hpp"

#include <cstring>

#include <fmt/format.h>

namespace vistel::wire {
namespace {

std::uint32_t readLength(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

}  // namespace

void appendFrame(std::span<const std::uint8_t> payload, std::vector<std::uint8_t>& out) {
  const auto n = static_cast<std::uint32_t>(payload.size());
  const std::uint8_t header[kFrameHeaderBytes] = {
      static_cast<std::uint8_t>(n), static_cast<std::uint8_t>(n >> 8),
      static_cast<std::uint8_t>(n >> 16), static_cast<std::uint8_t>(n >> 24)};
  out.insert(out.end(), header, header + kFrameHeaderBytes);
  out.insert(out.end(), payload.begin(), payload.end());
}

bool FrameDecoder::push(std::span<const std::uint8_t> bytes) {
  if (broken()) return false;
  // Drop what was already handed out before growing the buffer.
  if (read_pos_ > 0 && (read_pos_ == buffer_.size() || read_pos_ >= buffer_.size() / 2)) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(read_pos_));
    read_pos_ = 0;
  }
  buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
  return checkHeader();
}

bool FrameDecoder::checkHeader() {
  if (buffered() < kFrameHeaderBytes) return true;
  const std::uint32_t n = readLength(buffer_.data() + read_pos_);
  if (n > max_frame_bytes_) {
    error_ = fmt::format("frame of {} bytes exceeds the limit of {} bytes", n, max_frame_bytes_);
    buffer_.clear();
    read_pos_ = 0;
    return false;
  }
  return true;
}

std::optional<std::span<const std::uint8_t>> FrameDecoder::next() {
  if (broken() || buffered() < kFrameHeaderBytes) return std::nullopt;
  const std::uint32_t n = readLength(buffer_.data() + read_pos_);
  if (n > max_frame_bytes_ || buffered() < kFrameHeaderBytes + n) return std::nullopt;
  std::span<const std::uint8_t> payload(buffer_.data() + read_pos_ + kFrameHeaderBytes, n);
  read_pos_ += kFrameHeaderBytes + n;
  // Validate the following frame's header now, so an oversized one is seen early.
  checkHeader();
  return payload;
}

}  // namespace vistel::wire
