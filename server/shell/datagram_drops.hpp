// Datagrams the server drops before they reach a room's logic or inside it (issue 20,
// finding 9): counted by class of reason for /metrics (vistel_datagrams_dropped_total) and
// summarised in the log at most once per interval at info level, so a flood shows up
// without flooding the log.
//
// The classes: "bad header" (not a vistel datagram, truncated, a client-bound type),
// "unknown key" (no such member, or not sealed with its key: a bad tag), "unverified
// address" (before the member's hello, or from another address than the bound one),
// "rate" (a sender over a rate limit), "bad payload" (a header and seal that check out
// over a body that does not), "replay" (a counter the receiver has seen, or one older
// than its window; proto/WIRE.md §3.9) and "other".
//
// Thread-safe: the UDP receive handler and every room strand record drops; counts are
// relaxed atomics, the log interval sits behind a mutex taken only when a drop happens.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

namespace vistel::server {

enum class DropClass {
  kBadHeader,
  kUnknownKey,
  kUnverifiedAddress,
  kRate,
  kBadPayload,
  kOther,
  kReplay,
};
inline constexpr int kDropClassCount = 7;

// The metric label of a class ("bad header", ...).
std::string_view dropClassName(DropClass c);
// The class of a drop reason phrase of routeDatagram (server_core.hpp) or Room ("bad key",
// "wrong endpoint", ...); an unknown phrase is kOther.
DropClass classifyDropReason(std::string_view reason);

class DatagramDrops {
 public:
  // interval_s: the least time between two log summaries (> 0).
  explicit DatagramDrops(double interval_s = 10.0) : interval_s_(interval_s) {}

  // One dropped datagram at server time `now` (seconds, non-decreasing per caller; any
  // thread). Returns the summary line to log at info when the interval since the last one
  // has passed ("dropped N datagrams in the last T s: 3 bad header, ..."), else nullopt.
  std::optional<std::string> add(std::string_view reason, double now);

  std::uint64_t count(DropClass c) const {
    return counts_[static_cast<std::size_t>(c)].load(std::memory_order_relaxed);
  }
  std::uint64_t total() const;
  // Totals by class name, every class present (0 included), for a /metrics scrape.
  std::map<std::string, std::uint64_t> byReason() const;

 private:
  double interval_s_;
  std::array<std::atomic<std::uint64_t>, kDropClassCount> counts_{};
  std::mutex mutex_;
  double logged_at_ = -1e300;                           // last summary (mutex_)
  std::array<std::uint64_t, kDropClassCount> since_{};  // drops since it, by class (mutex_)
};

}  // namespace vistel::server
