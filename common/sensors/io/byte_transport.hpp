// ByteTransport: a byte pipe to a device — a serial port, a USB bulk pair, or a fake in
// tests. Drivers speak their protocol over it and never see the OS.
//
// read() waits at most timeout_s for at least one byte and returns what is there (up to the
// buffer's size). kUnplugged means the device is gone (the port hung up, closed, or USB
// reported no device); kFailed is any other OS error. Messages name the device and the OS
// reason. Not thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace vistel {

enum class IoStatus : std::uint8_t { kOk, kTimeout, kUnplugged, kFailed };

struct IoResult {
  IoStatus status = IoStatus::kOk;
  std::size_t bytes = 0;
  std::string message;  // empty on kOk
};

class ByteTransport {
 public:
  virtual ~ByteTransport() = default;
  virtual IoResult read(std::span<std::uint8_t> buffer, double timeout_s) = 0;
  // Writes every byte (waiting at most timeout_s for room) or fails.
  virtual IoResult write(std::span<const std::uint8_t> bytes, double timeout_s) = 0;
  // Drops whatever is waiting to be read.
  virtual void discardInput() = 0;
  virtual std::string describe() const = 0;
};

// A command string as the bytes write() takes.
inline std::span<const std::uint8_t> bytesOf(std::string_view s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

}  // namespace vistel
