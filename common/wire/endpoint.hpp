// A network endpoint as the protocol cores see it (no sockets): a 16-byte IPv6 address
// (IPv4 as v4-mapped ::ffff:a.b.c.d) and a port. The Asio shells convert.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>

namespace vistel::wire {

struct Endpoint {
  std::array<std::uint8_t, 16> address{};
  std::uint16_t port = 0;

  bool operator==(const Endpoint&) const = default;

  // An IPv4 endpoint (a.b.c.d in host order: 0x7F000001 is 127.0.0.1).
  static Endpoint ipv4(std::uint32_t address_host_order, std::uint16_t port);
  bool isIpv4() const;
  std::uint32_t ipv4Address() const;  // host order; only when isIpv4()
  // "127.0.0.1:7400" or "[::1]:7400".
  std::string toString() const;
};

struct EndpointHash {
  std::size_t operator()(const Endpoint& e) const;
};

}  // namespace vistel::wire
