// Counting and logging of rejected input: every dropped packet or peer gets a reason,
// counted per reason (tests read the counts) and logged through spdlog. So that a flood
// of garbage cannot flood the log, at most kWarnBurst drops per kWindowSeconds are
// logged at warn level; the rest go to debug.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>

namespace vistel::server {

class DropLog {
 public:
  static constexpr int kWarnBurst = 20;
  static constexpr double kWindowSeconds = 10.0;

  explicit DropLog(std::string scope) : scope_(std::move(scope)) {}

  // Records one drop: reason is a short fixed phrase ("bad key"), detail names the
  // sender and values.
  void drop(double now, std::string_view reason, std::string_view detail);

  std::uint64_t total() const { return total_; }
  std::uint64_t count(std::string_view reason) const;
  const std::map<std::string, std::uint64_t, std::less<>>& counts() const { return counts_; }

 private:
  std::string scope_;
  std::map<std::string, std::uint64_t, std::less<>> counts_;
  std::uint64_t total_ = 0;
  double window_start_ = -1e300;
  int warned_in_window_ = 0;
};

}  // namespace vistel::server
