#include "server/shell/connection_limits.hpp"

namespace vistel::server {

std::string_view ConnectionLimits::admit(const std::string& address, bool loopback) {
  std::string_view reason;
  if (max_total_ > 0 && open_ >= max_total_) {
    reason = "connection limit";
  } else if (max_per_address_ > 0 && (!loopback || limit_loopback_) &&
             openFrom(address) >= max_per_address_) {
    reason = "connections per address";
  }
  if (!reason.empty()) {
    ++refusals_[std::string(reason)];
    return reason;
  }
  ++open_;
  ++per_address_[address];
  return {};
}

void ConnectionLimits::release(const std::string& address) {
  auto it = per_address_.find(address);
  if (it == per_address_.end()) return;  // never admitted
  if (open_ > 0) --open_;
  if (--it->second <= 0) per_address_.erase(it);
}

int ConnectionLimits::openFrom(const std::string& address) const {
  auto it = per_address_.find(address);
  return it == per_address_.end() ? 0 : it->second;
}

}  // namespace vistel::server
