#include "common/wire/endpoint.hpp"

#include <fmt/format.h>

#include "common/base/hash.hpp"

namespace vistel::wire {

Endpoint Endpoint::ipv4(std::uint32_t address_host_order, std::uint16_t port) {
  Endpoint e;
  e.address[10] = 0xFF;
  e.address[11] = 0xFF;
  for (int k = 0; k < 4; ++k) {
    e.address[static_cast<std::size_t>(12 + k)] =
        static_cast<std::uint8_t>(address_host_order >> (24 - 8 * k));
  }
  e.port = port;
  return e;
}

bool Endpoint::isIpv4() const {
  for (int k = 0; k < 10; ++k) {
    if (address[static_cast<std::size_t>(k)] != 0) return false;
  }
  return address[10] == 0xFF && address[11] == 0xFF;
}

std::uint32_t Endpoint::ipv4Address() const {
  return (static_cast<std::uint32_t>(address[12]) << 24) |
         (static_cast<std::uint32_t>(address[13]) << 16) |
         (static_cast<std::uint32_t>(address[14]) << 8) | static_cast<std::uint32_t>(address[15]);
}

std::string Endpoint::toString() const {
  if (isIpv4()) {
    return fmt::format("{}.{}.{}.{}:{}", address[12], address[13], address[14], address[15], port);
  }
  std::string s = "[";
  for (int k = 0; k < 16; k += 2) {
    if (k > 0) s += ':';
    s += fmt::format("{:x}", (address[static_cast<std::size_t>(k)] << 8) |
                                 address[static_cast<std::size_t>(k + 1)]);
  }
  return s + fmt::format("]:{}", port);
}

std::size_t EndpointHash::operator()(const Endpoint& e) const {
  const std::uint64_t h = fnv1a64(e.address.data(), e.address.size());
  return static_cast<std::size_t>(fnv1a64(&e.port, sizeof e.port, h));
}

}  // namespace vistel::wire
