#include "server/core/drop_log.hpp"

#include <spdlog/spdlog.h>

namespace vistel::server {

void DropLog::drop(double now, std::string_view reason, std::string_view detail) {
  // Count by reason.
  auto it = counts_.find(reason);
  if (it == counts_.end()) it = counts_.emplace(std::string(reason), 0).first;
  ++it->second;
  ++total_;

  // Log: warn for the first few in each window, debug afterwards.
  if (now - window_start_ >= kWindowSeconds) {
    if (warned_in_window_ >= kWarnBurst) {
      spdlog::warn("{}: further drops in the last {:.0f} s were logged at debug level", scope_,
                   kWindowSeconds);
    }
    window_start_ = now;
    warned_in_window_ = 0;
  }
  if (warned_in_window_ < kWarnBurst) {
    ++warned_in_window_;
    spdlog::warn("{}: dropped: {} ({})", scope_, reason, detail);
  } else {
    spdlog::debug("{}: dropped: {} ({})", scope_, reason, detail);
  }
}

std::uint64_t DropLog::count(std::string_view reason) const {
  auto it = counts_.find(reason);
  return it == counts_.end() ? 0 : it->second;
}

}  // namespace vistel::server
