#include "common/sensors/io/serial_transport.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

namespace vistel {
namespace {

bool baudConstant(int baud, speed_t& out) {
  switch (baud) {
    case 1200:
      out = B1200;
      return true;
    case 2400:
      out = B2400;
      return true;
    case 4800:
      out = B4800;
      return true;
    case 9600:
      out = B9600;
      return true;
    case 19200:
      out = B19200;
      return true;
    case 38400:
      out = B38400;
      return true;
    case 57600:
      out = B57600;
      return true;
    case 115200:
      out = B115200;
      return true;
    case 230400:
      out = B230400;
      return true;
    case 460800:
      out = B460800;
      return true;
    case 921600:
      out = B921600;
      return true;
    default:
      return false;
  }
}

int pollTimeoutMs(double timeout_s) {
  if (!(timeout_s > 0.0)) return 0;
  return static_cast<int>(std::ceil(std::min(timeout_s, 3600.0) * 1000.0));
}

}  // namespace

Result<std::unique_ptr<SerialTransport>> SerialTransport::open(const std::string& path, int baud) {
  speed_t speed;
  if (!baudConstant(baud, speed)) return fail("{}: unsupported baud rate {}", path, baud);
  std::unique_ptr<SerialTransport> t(new SerialTransport());
  t->path_ = path;
  t->fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (t->fd_ < 0) return fail("{}: cannot open serial port: {}", path, std::strerror(errno));
  termios tio{};
  if (::tcgetattr(t->fd_, &tio) != 0) {
    return fail("{}: not a serial port: {}", path, std::strerror(errno));
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS);
  tio.c_cflag = (tio.c_cflag & ~static_cast<tcflag_t>(CSIZE)) | CS8;
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  ::cfsetispeed(&tio, speed);
  ::cfsetospeed(&tio, speed);
  if (::tcsetattr(t->fd_, TCSANOW, &tio) != 0) {
    return fail("{}: cannot configure the port: {}", path, std::strerror(errno));
  }
  ::tcflush(t->fd_, TCIOFLUSH);
  return t;
}

SerialTransport::~SerialTransport() {
  if (fd_ >= 0) ::close(fd_);
}

IoResult SerialTransport::read(std::span<std::uint8_t> buffer, double timeout_s) {
  pollfd p{fd_, POLLIN, 0};
  for (;;) {
    const int r = ::poll(&p, 1, pollTimeoutMs(timeout_s));
    if (r < 0) {
      if (errno == EINTR) continue;
      return {IoStatus::kFailed, 0,
              fmt::format("{}: poll failed: {}", path_, std::strerror(errno))};
    }
    if (r == 0) return {IoStatus::kTimeout, 0, fmt::format("{}: no data", path_)};
    break;
  }
  const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
  if (n > 0) return {IoStatus::kOk, static_cast<std::size_t>(n), {}};
  if (n == 0 || errno == EIO || (p.revents & (POLLHUP | POLLERR)) != 0) {
    return {IoStatus::kUnplugged, 0,
            fmt::format("{}: device unplugged (the port hung up{})", path_,
                        n == 0 ? "" : ": " + std::string(std::strerror(errno)))};
  }
  if (errno == EAGAIN || errno == EINTR)
    return {IoStatus::kTimeout, 0, fmt::format("{}: no data", path_)};
  return {IoStatus::kFailed, 0, fmt::format("{}: read failed: {}", path_, std::strerror(errno))};
}

IoResult SerialTransport::write(std::span<const std::uint8_t> bytes, double timeout_s) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      pollfd p{fd_, POLLOUT, 0};
      const int r = ::poll(&p, 1, pollTimeoutMs(timeout_s));
      if (r == 0) return {IoStatus::kTimeout, done, fmt::format("{}: write timed out", path_)};
      if (r > 0 && (p.revents & POLLOUT) != 0) continue;
      if (r > 0 && (p.revents & (POLLHUP | POLLERR)) != 0) {
        return {IoStatus::kUnplugged, done,
                fmt::format("{}: device unplugged (hung up while writing)", path_)};
      }
      continue;
    }
    if (n < 0 && (errno == EIO || errno == ENXIO || errno == ENODEV)) {
      return {IoStatus::kUnplugged, done,
              fmt::format("{}: device unplugged ({})", path_, std::strerror(errno))};
    }
    return {IoStatus::kFailed, done,
            fmt::format("{}: write failed: {}", path_, std::strerror(errno))};
  }
  return {IoStatus::kOk, done, {}};
}

void SerialTransport::discardInput() { ::tcflush(fd_, TCIFLUSH); }

}  // namespace vistel
