// Plain HTTP and address helpers for the command-line tests that read a live server's
// /metrics (loopback only).
#pragma once

#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cstdint>
#include <string>

#include "tests/integration/raw_control.hpp"

namespace vistel::test {

// The port of "host:port".
inline std::uint16_t portOf(const std::string& address) {
  return static_cast<std::uint16_t>(std::stoi(address.substr(address.rfind(':') + 1)));
}

// Sends raw bytes to 127.0.0.1:port on a new connection and reads until the peer closes
// or `wait_s` pass without data ("" when it cannot connect).
inline std::string sendAndRead(std::uint16_t port, const std::string& bytes, double wait_s) {
  const int fd = connectLoopback(port);
  if (fd < 0) return {};
  ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
  timeval timeout{
      static_cast<time_t>(wait_s),
      static_cast<suseconds_t>((wait_s - static_cast<double>(static_cast<time_t>(wait_s))) * 1e6)};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  std::string out;
  char buffer[4096];
  while (true) {
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    out.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return out;
}

// GET path from 127.0.0.1:port; the whole response ("" on failure; 10 s receive timeout).
inline std::string httpGet(std::uint16_t port, const std::string& path) {
  return sendAndRead(
      port, "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", 10.0);
}

}  // namespace vistel::test
