// SerialTransport: a POSIX serial port (termios) as a ByteTransport — raw 8N1, no flow
// control, the given baud rate. Opens real ports (/dev/ttyUSB0, /dev/ttyS0) and
// pseudo-terminals (/dev/pts/N) alike; a pty whose other side closed reads as unplugged.
#pragma once

#include <memory>
#include <string>

#include "common/base/result.hpp"
#include "common/sensors/io/byte_transport.hpp"

namespace vistel {

class SerialTransport final : public ByteTransport {
 public:
  // Fails naming the port and the OS reason (no such device, permission, not a tty) or an
  // unsupported baud rate.
  static Result<std::unique_ptr<SerialTransport>> open(const std::string& path, int baud);
  ~SerialTransport() override;

  IoResult read(std::span<std::uint8_t> buffer, double timeout_s) override;
  IoResult write(std::span<const std::uint8_t> bytes, double timeout_s) override;
  void discardInput() override;
  std::string describe() const override { return path_; }

 private:
  SerialTransport() = default;
  int fd_ = -1;
  std::string path_;
};

}  // namespace vistel
